// The Python module `featherdrive`: thin pybind11 bindings over the C++ API with the same names.
// Vectors come back as read-only numpy views onto the Simulation's Eigen vectors (no copy; the
// view keeps the Simulation alive); arrays going in are checked for shape and dtype here so that
// a wrong one raises ValueError naming it. C++ std::invalid_argument (ModelError, InputError) ->
// ValueError, DivergenceError (std::runtime_error) -> RuntimeError, with the C++ message.
#include "bindings.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

PYBIND11_MODULE(featherdrive, m) {
  main_thread_id =
      py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
  m.doc() =
      "featherdrive: articulated robots in reduced coordinates with implicit PD joint drives "
      "solved as NVIDIA PhysX 5 does (PGS or TGS).\n\n"
      "Vectors read from a Simulation (q, qd, drive_force, ...) are read-only numpy views onto "
      "its state: they follow later steps and stay valid for the simulation's life (set_q, "
      "set_options, load_checkpoint, ... write into the same memory); copy them "
      "(numpy.array(sim.q)) to keep a snapshot. Batch states and the settings read back "
      "(drive(), options, ...) are copies.\n\n"
      "Threads: a Simulation or Batch may be shared between Python threads. Each has a lock "
      "that every method holds while it reads or writes the object (a copy from Batch.sim(i) "
      "shares its batch's lock), so calls on one object run one after another, each whole: "
      "four threads calling step(n) make exactly 4n steps, the same as one thread. A method "
      "waits for the lock without the GIL; step() runs without the GIL, so threads stepping "
      "different objects run in parallel. Views are not synchronised: reading sim.q while "
      "another thread steps sim reads values being written; read views when no step runs.\n\n"
      "Ctrl-C interrupts step() (Simulation and Batch) between two steps: KeyboardInterrupt, "
      "with the state of the last whole step (step_count tells how many were made).\n\n"
      "Integers (counts, indices, iterations, threads) are int, numpy integers or any object "
      "with __index__; bool and float are refused (TypeError); a value out of range raises "
      "ValueError naming the argument and the value, before anything is narrowed to 32 bits.\n\n"
      "Bad values raise ValueError, wrong types TypeError, a diverging step RuntimeError "
      "(DivergenceError), with the C++ message.";

  // Errors: subclasses of the Python exceptions the C++ base classes map to.
  py::register_exception<DivergenceError>(m, "DivergenceError", PyExc_RuntimeError).doc() =
      "A step would produce a non-finite value; the simulation keeps its state from "
      "before that step. A RuntimeError.";
  py::register_exception<ModelError>(m, "ModelError", PyExc_ValueError).doc() =
      "Bad model input (ModelBuilder): names the link or joint, field and value. A ValueError.";
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError).doc() =
      "A bad input file (URDF, scene): names the file, element or key and value. A ValueError.";

  bind_settings(m);
  bind_model(m);
  bind_simulation(m);
  bind_batch(m);
  bind_io(m);
  bind_mjcf(m);
  bind_dynamics(m);
  bind_names(m);
  bind_mujoco_bridge(m);
  bind_delay(m);
  bind_sweep(m);
  bind_fit(m);
  bind_view(m);
  bind_joints(m);
  bind_simd(m);
  bind_check(m);
  bind_contact(m);
  bind_settings_value(m);
  bind_row_kinds(m);
}
