// Shared by the files of the Python module `featherdrive` (python/*.cpp): argument converters
// with their error messages, the per-object locks and the holders. Inline, in one namespace, so
// that the files may also be compiled together (CMake unity build, python/CMakeLists.txt).
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <exception>
#include <functional>
#include <initializer_list>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "featherdrive/algorithm/center_of_mass.hpp"
#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/energy.hpp"
#include "featherdrive/algorithm/floating_base.hpp"
#include "featherdrive/algorithm/jacobian.hpp"
#include "featherdrive/algorithm/kinematics.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "featherdrive/io/checkpoint.hpp"
#include "featherdrive/io/scene.hpp"
#include "featherdrive/io/urdf.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/batch.hpp"
#include "featherdrive/sim/control_step.hpp"
#include "featherdrive/sim/simulation.hpp"

namespace py = pybind11;

namespace featherdrive::python {

// The parts of the module, one per file, registered by module.cpp in this order (a later one may
// add methods to an earlier one's classes).
void bind_settings(py::module_& m);
void bind_model(py::module_& m);
void bind_simulation(py::module_& m);
void bind_batch(py::module_& m);
void bind_io(py::module_& m);
void bind_mjcf(py::module_& m);  // after bind_io: MjcfRobot is a UrdfRobot
void bind_dynamics(py::module_& m);
void bind_names(py::module_& m);
void bind_mujoco_bridge(py::module_& m);  // bind_mujoco_bridge.cpp
void bind_delay(py::module_& m);
void bind_sweep(py::module_& m);
void bind_fit(py::module_& m);  // after bind_io: it extends Scene
void bind_view(py::module_& m);  // bind_view.cpp: fd.view, fd.link_world_poses
void bind_joints(py::module_& m);  // after bind_io: it extends Scene
void bind_simd(py::module_& m);  // bind_simd.cpp: available_simd_isas, a deprecated shim
void bind_check(py::module_& m);
/// An instruction set by name ('sse2', 'avx2', 'avx512'), None for the default (bind_batch.cpp).
std::optional<SimdIsa> to_isa(py::handle obj);  // bind_check.cpp: fd.check
void bind_contact(py::module_& m);  // bind_contact.cpp: after bind_io (UrdfRobot, Scene)
/// bind_settings_value.cpp: fd.Settings and what takes or gives one; after every class it names.
void bind_settings_value(py::module_& m);
void bind_row_kinds(py::module_& m);  // after bind_settings_value: it extends Settings

using ModelPtr = std::shared_ptr<Model>;
constexpr long long kIntMax = std::numeric_limits<int>::max();

// ---- integers -------------------------------------------------------------------------------
// Every integer from Python is read in 64 bits and range-checked before it is narrowed: ValueError
// naming the argument and the value. int, numpy integers and anything with __index__ are integers;
// bool is refused (True as a count or an index is a mistake) and so are floats: TypeError.

inline std::string type_name(py::handle obj) {
  return py::str(py::type::handle_of(obj).attr("__name__")).cast<std::string>();
}

inline bool is_integer(py::handle obj) {
  if (PyBool_Check(obj.ptr())) return false;
  if (PyLong_Check(obj.ptr())) return true;
  if (!PyIndex_Check(obj.ptr())) return false;
  return !py::isinstance(obj, py::module_::import("numpy").attr("bool_"));
}

/// obj as a 64-bit integer in [lo, hi].
inline long long to_int64(py::handle obj, const std::string& what, long long lo, long long hi) {
  if (!is_integer(obj))
    throw py::type_error(what + " must be an integer, not " + type_name(obj) + " (" +
                         py::repr(obj).cast<std::string>() + ")");
  const auto index = py::reinterpret_steal<py::object>(PyNumber_Index(obj.ptr()));
  if (!index) throw py::error_already_set();
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
  if (v == -1 && PyErr_Occurred()) throw py::error_already_set();
  if (overflow != 0 || v < lo || v > hi)
    throw py::value_error(what + " = " + py::str(index).cast<std::string>() + " is out of range [" +
                          std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

inline int to_int(py::handle obj, const std::string& what, long long lo, long long hi = kIntMax) {
  return static_cast<int>(to_int64(obj, what, lo, std::min(hi, kIntMax)));
}

/// A str argument as UTF-8; TypeError naming `what` for anything else.
inline std::string to_str(py::handle obj, const std::string& what) {
  if (!py::isinstance<py::str>(obj))
    throw py::type_error(what + " must be a str, not " + type_name(obj));
  Py_ssize_t size = 0;
  const char* data = PyUnicode_AsUTF8AndSize(obj.ptr(), &size);
  if (!data) throw py::error_already_set();
  return std::string(data, static_cast<size_t>(size));
}

/// A joint or link given as a name or an index, read while the GIL is held; resolved against the
/// model later, under the object's lock.
struct NameOrIndex {
  std::string name;
  long long index = -1;
  bool named = false;
};

inline NameOrIndex to_name_or_index(py::handle obj, const std::string& what, const char* expected) {
  if (py::isinstance<py::str>(obj)) return {to_str(obj, what), -1, true};
  if (!is_integer(obj))
    throw py::type_error(what + " = " + py::repr(obj).cast<std::string>() + ": expected " +
                         expected + ", not " + type_name(obj));
  return {"",
          to_int64(obj, what, std::numeric_limits<long long>::min(),
                   std::numeric_limits<long long>::max()),
          false};
}

// ---- per-object locks -----------------------------------------------------------------------
// Python threads may share a Simulation or Batch: every binding that reads or writes one holds
// its lock, so calls on one object are serialised (whole calls: a step(n) runs its n steps before
// another call on that object starts). The lock is first come, first served (a ticket lock): a
// call that waits gets its turn after the calls that asked before it, so a thread stepping in a
// loop cannot starve another. The lock is waited for with the GIL released, so that its holder
// can re-take the GIL (step() runs without it); the main thread's wait answers Ctrl-C (its ticket
// is then given up). The table maps an object's address to its lock and is only touched with the
// GIL held, which guards it. A copy inside a Batch maps to the batch's lock (Batch.sim registers
// it). The entries of an object go when the Python object owning it is freed (the holders'
// deleters).

class ObjectLock {
 public:
  using Ticket = unsigned long long;
  /// Takes the lock if no one holds it or waits for it.
  bool try_acquire() {
    std::lock_guard<std::mutex> guard(mutex_);
    if (serving_ != next_) return false;
    ++next_;
    return true;
  }
  /// A place in the queue; the lock is the caller's once granted(ticket).
  Ticket request() {
    std::lock_guard<std::mutex> guard(mutex_);
    return next_++;
  }
  /// Waits until the ticket's turn (or the timeout): whether it came.
  bool wait(Ticket ticket, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> guard(mutex_);
    return turn_.wait_for(guard, timeout, [&] { return serving_ == ticket; });
  }
  void wait(Ticket ticket) {
    std::unique_lock<std::mutex> guard(mutex_);
    turn_.wait(guard, [&] { return serving_ == ticket; });
  }
  void release() {
    std::lock_guard<std::mutex> guard(mutex_);
    advance();
  }
  /// Gives a ticket up (its waiter left): passed on if its turn has come, else skipped later.
  void abandon(Ticket ticket) {
    std::lock_guard<std::mutex> guard(mutex_);
    if (serving_ == ticket)
      advance();
    else
      abandoned_.push_back(ticket);
  }

 private:
  void advance() {
    ++serving_;
    for (auto it = std::find(abandoned_.begin(), abandoned_.end(), serving_);
         it != abandoned_.end(); it = std::find(abandoned_.begin(), abandoned_.end(), serving_)) {
      abandoned_.erase(it);
      ++serving_;
    }
    turn_.notify_all();
  }
  std::mutex mutex_;
  std::condition_variable turn_;
  Ticket next_ = 0;     // the next ticket to hand out
  Ticket serving_ = 0;  // the ticket that holds the lock (free when serving_ == next_)
  std::vector<Ticket> abandoned_;
};

using LockTable = std::unordered_map<const void*, std::shared_ptr<ObjectLock>>;

inline LockTable& lock_table() {
  static auto* table = new LockTable;  // never destroyed: deleters may run during interpreter exit
  return *table;
}

inline std::shared_ptr<ObjectLock> lock_for(const void* object) {
  std::shared_ptr<ObjectLock>& lock = lock_table()[object];
  if (!lock) lock = std::make_shared<ObjectLock>();
  return lock;
}

inline unsigned long main_thread_id = 0;  // set at import

inline bool on_main_thread() {
  return PyThread_get_thread_ident() == main_thread_id;
}

/// Raises KeyboardInterrupt (or what a signal handler raised) if a signal came; call without the
/// GIL, on the main thread (the only one Python runs signal handlers on).
inline void check_signals() {
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
}

/// Holds an object's lock for its scope.
class Hold {
 public:
  /// With the GIL held: waits without it if another thread holds the lock or waits for it.
  explicit Hold(const void* object) : lock_(lock_for(object)) {
    if (lock_->try_acquire()) return;
    const ObjectLock::Ticket ticket = lock_->request();
    py::gil_scoped_release nogil;
    wait(ticket);
  }
  /// Without the GIL (lock from lock_for, taken with the GIL).
  explicit Hold(std::shared_ptr<ObjectLock> lock) : lock_(std::move(lock)) {
    wait(lock_->request());
  }
  ~Hold() { lock_->release(); }
  Hold(const Hold&) = delete;
  Hold& operator=(const Hold&) = delete;

 private:
  void wait(ObjectLock::Ticket ticket) {
    if (!on_main_thread()) return lock_->wait(ticket);
    try {
      while (!lock_->wait(ticket, std::chrono::milliseconds(20))) check_signals();
    } catch (...) {
      lock_->abandon(ticket);
      throw;
    }
  }
  std::shared_ptr<ObjectLock> lock_;
};

/// f() holding object's lock, with the GIL.
template <class T, class F>
auto locked(const T& object, F&& f) {
  Hold hold(&object);
  return f();
}

/// f() holding object's lock, without the GIL (file input and output); f must not touch Python.
template <class T, class F>
void locked_nogil(const T& object, F&& f) {
  auto lock = lock_for(&object);
  py::gil_scoped_release nogil;
  Hold hold(std::move(lock));
  f();
}

/// step(n) for n = count in all, without the GIL, holding object's lock. On the main thread the
/// steps go in chunks with a check for Ctrl-C between them (KeyboardInterrupt with the state of
/// the last whole step); chunks double while they take under 2 ms, so a long run checks every few
/// ms and step(1) costs no check at all.
template <class T, class Step>
void step_in_chunks(const T& object, int count, Step step) {
  auto lock = lock_for(&object);
  py::gil_scoped_release nogil;
  Hold hold(std::move(lock));
  if (count <= 1 || !on_main_thread()) return step(count);
  using Clock = std::chrono::steady_clock;
  int done = 0, chunk = 1;
  while (done < count) {
    const int n = std::min(chunk, count - done);
    const auto start = Clock::now();
    step(n);
    done += n;
    if (done == count) break;
    check_signals();
    const auto took = Clock::now() - start;
    if (took < std::chrono::milliseconds(2) && chunk <= kIntMax / 2)
      chunk *= 2;
    else if (took > std::chrono::milliseconds(20) && chunk > 1)
      chunk /= 2;
  }
}

// Python owns Simulations and Batches through these: freeing one drops its lock entries.
struct SimulationDeleter {
  void operator()(Simulation* sim) const {
    lock_table().erase(sim);
    delete sim;
  }
};
struct BatchDeleter {
  void operator()(Batch* batch) const {
    lock_table().erase(batch);
    for (int i = 0; i < batch->size(); ++i) lock_table().erase(&batch->sim(i));
    delete batch;
  }
};
using SimulationHolder = std::unique_ptr<Simulation, SimulationDeleter>;
using BatchHolder = std::unique_ptr<Batch, BatchDeleter>;

// Python holds models as shared_ptr<Model> (pybind11 needs a non-const holder); the bindings
// expose no way to change one, so it stays as immutable as the C++ shared_ptr<const Model>.
inline ModelPtr to_python(const std::shared_ptr<const Model>& model) {
  return std::const_pointer_cast<Model>(model);
}

inline std::string shape_of(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i)
    s << (i ? ", " : "") << a.shape(i) << (a.ndim() == 1 ? "," : "");
  s << ")";
  return s.str();
}

/// obj as a C-contiguous float64 array; ValueError naming `what` unless its dtype is real numbers.
inline py::array_t<double, py::array::c_style> as_float_array(py::handle obj,
                                                              const std::string& what) {
  py::array a = py::module_::import("numpy").attr("asarray")(obj);
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw std::invalid_argument(what + " has dtype " + py::str(a.dtype()).cast<std::string>() +
                                ": expected real numbers (float64)");
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
}

/// A vector of n values: an array of shape (n,), or a scalar for all n.
inline VecX to_vector(py::handle obj, Eigen::Index n, const std::string& what,
                      bool scalar_ok = false) {
  const auto a = as_float_array(obj, what);
  if (scalar_ok && a.ndim() == 0) return VecX::Constant(n, *a.data());
  if (a.ndim() != 1 || a.shape(0) != n)
    throw std::invalid_argument(what + " has shape " + shape_of(a) + ", expected (" +
                                std::to_string(n) + ",)");
  VecX v(n);
  if (n > 0) std::memcpy(v.data(), a.data(), sizeof(double) * static_cast<size_t>(n));
  return v;
}

inline Vec3 to_vec3(py::handle obj, const std::string& what) {
  return to_vector(obj, 3, what);
}

/// to_vector with every entry finite: ValueError naming the entry and its value.
inline VecX to_finite_vector(py::handle obj, Eigen::Index n, const std::string& what) {
  VecX v = to_vector(obj, n, what);
  for (Eigen::Index i = 0; i < n; ++i)
    if (!std::isfinite(v[i]))
      throw std::invalid_argument(what + "[" + std::to_string(i) + "] = " +
                                  py::repr(py::float_(v[i])).cast<std::string>() +
                                  ": must be finite");
  return v;
}

inline Mat3 to_mat3(py::handle obj, const std::string& what) {
  const auto a = as_float_array(obj, what);
  if (a.ndim() != 2 || a.shape(0) != 3 || a.shape(1) != 3)
    throw std::invalid_argument(what + " has shape " + shape_of(a) + ", expected (3, 3)");
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = a.at(i, j);
  return m;
}

/// Values for k environments with `cols` columns: a scalar (unless scalar_ok is false) or one row
/// (cols,) for all of them, as (1, cols); or (k, cols), one row each.
inline RowMatrix to_rows(py::handle obj, size_t k, Eigen::Index cols, const std::string& what,
                         bool scalar_ok = true) {
  const auto a = as_float_array(obj, what);
  const auto rows = static_cast<Eigen::Index>(k);
  if ((scalar_ok && a.ndim() == 0) || (a.ndim() == 1 && a.shape(0) == cols)) {
    RowMatrix m(1, cols);
    for (Eigen::Index j = 0; j < cols; ++j) m(0, j) = a.data()[a.ndim() == 0 ? 0 : j];
    return m;
  }
  if (a.ndim() != 2 || a.shape(0) != rows || a.shape(1) != cols)
    throw std::invalid_argument(what + " has shape " + shape_of(a) + ", expected (" +
                                std::to_string(rows) + ", " + std::to_string(cols) + ") or (" +
                                std::to_string(cols) + ",)" + (scalar_ok ? " or a scalar" : ""));
  RowMatrix m(rows, cols);
  if (m.size() > 0) std::memcpy(m.data(), a.data(), sizeof(double) * static_cast<size_t>(m.size()));
  return m;
}

/// A new array the caller cannot write to (a copy of a setting, not a view of the state).
inline py::array read_only(RowMatrix m) {
  py::array a = py::cast(std::move(m));
  a.attr("flags").attr("writeable") = false;
  return a;
}

/// env_ids of a batch of n: None for all, an integer, or a sequence or array of integers (range
/// and repeats are checked by Batch).
inline std::vector<int> to_env_ids(py::handle obj, int n) {
  std::vector<int> ids;
  if (obj.is_none()) {
    for (int i = 0; i < n; ++i) ids.push_back(i);
    return ids;
  }
  constexpr long long lo = std::numeric_limits<int>::min();
  // A numpy array has __index__ too (raising for more than one element): not an integer here.
  if (!py::isinstance<py::array>(obj) && is_integer(obj)) return {to_int(obj, "env_ids", lo)};
  const py::array a = py::module_::import("numpy").attr("asarray")(obj);
  const char kind = a.dtype().kind();
  if (a.size() > 0 && kind != 'i' && kind != 'u')
    throw py::type_error("env_ids must hold integers, not " +
                         py::str(a.dtype()).cast<std::string>());
  if (a.ndim() != 1)
    throw std::invalid_argument("env_ids has shape " + shape_of(a) + ", expected (k,)");
  const py::list values = a.attr("tolist")();
  for (size_t j = 0; j < values.size(); ++j)
    ids.push_back(to_int(values[j], "env_ids[" + std::to_string(j) + "]", lo));
  return ids;
}

/// Batch.observe's field names.
inline std::vector<Observation> to_observations(py::handle fields) {
  static const std::pair<const char*, Observation> kNames[] = {
      {"q", Observation::q},
      {"qd", Observation::qd},
      {"applied_force", Observation::applied_force},
      {"drive_force", Observation::drive_force},
      {"limit_force", Observation::limit_force},
      {"friction_force", Observation::friction_force},
      {"velocity_limit_force", Observation::velocity_limit_force},
      {"target_position", Observation::target_position},
      {"target_velocity", Observation::target_velocity}};
  if (py::isinstance<py::str>(fields))
    throw py::type_error("observe: fields must be a list of names, not a str");
  std::vector<Observation> out;
  for (py::handle f : py::iter(fields)) {
    const std::string name = to_str(f, "observe: field");
    bool found = false;
    for (const auto& [n, o] : kNames)
      if (name == n) {
        out.push_back(o);
        found = true;
      }
    if (!found)
      throw std::invalid_argument("observe: field '" + name +
                                  "' is not one of q, qd, "
                                  "applied_force, drive_force, limit_force, friction_force, "
                                  "velocity_limit_force, target_position, target_velocity");
  }
  return out;
}

// An enum argument: the enum itself or its name; ValueError for an unknown name, TypeError for
// any other type.
template <class E>
E to_enum(py::handle obj, const char* what, std::initializer_list<std::pair<const char*, E>> names,
          const char* expected) {
  if (py::isinstance<E>(obj)) return obj.cast<E>();
  if (!py::isinstance<py::str>(obj))
    throw py::type_error(std::string(what) + " = " + py::repr(obj).cast<std::string>() +
                         ": expected " + expected + " or a " +
                         py::str(py::type::of<E>().attr("__name__")).cast<std::string>() +
                         ", not " + type_name(obj));
  const std::string s = to_str(obj, what);
  for (const auto& [name, value] : names)
    if (s == name) return value;
  throw std::invalid_argument(std::string(what) + " = '" + s + "': must be " + expected);
}

inline SolverType to_solver(py::handle obj) {
  return to_enum<SolverType>(obj, "solver", {{"pgs", SolverType::pgs}, {"tgs", SolverType::tgs}},
                             "'pgs' or 'tgs'");
}

inline DriveType to_drive_type(py::handle obj) {
  return to_enum<DriveType>(obj, "drive type",
                            {{"none", DriveType::none},
                             {"force", DriveType::force},
                             {"acceleration", DriveType::acceleration}},
                            "'none', 'force' or 'acceleration'");
}

inline UrdfEffort to_urdf_effort(py::handle obj) {
  return to_enum<UrdfEffort>(obj, "effort",
                             {{"none", UrdfEffort::none},
                              {"max_force", UrdfEffort::max_force},
                              {"effort_limit", UrdfEffort::effort_limit}},
                             "'none', 'max_force' or 'effort_limit'");
}

inline Compat to_compat(py::handle obj) {
  return to_enum<Compat>(obj, "compat", {{"none", Compat::none}, {"physx", Compat::physx}},
                         "'none' or 'physx'");
}

// Explicit actuators: the kind by name, the remotized table as an (n, 2) array or None.
inline ActuatorKind to_actuator_kind(py::handle obj) {
  return to_enum<ActuatorKind>(obj, "actuator kind",
                               {{"none", ActuatorKind::none},
                                {"ideal_pd", ActuatorKind::ideal_pd},
                                {"dc_motor", ActuatorKind::dc_motor},
                                {"remotized_pd", ActuatorKind::remotized_pd}},
                               "'none', 'ideal_pd', 'dc_motor' or 'remotized_pd'");
}

inline ActuatorIntegration to_actuator_integration(py::handle obj) {
  return to_enum<ActuatorIntegration>(obj, "integration",
                                      {{"explicit", ActuatorIntegration::explicit_law},
                                       {"implicit", ActuatorIntegration::implicit_law}},
                                      "'explicit' or 'implicit'");
}

inline std::vector<std::pair<double, double>> to_lookup(py::handle obj) {
  std::vector<std::pair<double, double>> table;
  if (obj.is_none()) return table;
  const auto a = as_float_array(obj, "lookup");
  if (a.ndim() != 2 || a.shape(1) != 2)
    throw std::invalid_argument("lookup has shape " + shape_of(a) +
                                ", expected (n, 2): rows of (position, max effort)");
  for (py::ssize_t i = 0; i < a.shape(0); ++i) table.emplace_back(a.at(i, 0), a.at(i, 1));
  return table;
}

inline ExplicitActuator make_actuator(ActuatorKind kind, double stiffness, double damping,
                                      double effort_limit, double saturation_effort,
                                      double velocity_limit, py::handle lookup, py::handle delay,
                                      py::handle integration) {
  ExplicitActuator a;
  a.kind = kind;
  a.stiffness = stiffness;
  a.damping = damping;
  a.effort_limit = effort_limit;
  a.saturation_effort = saturation_effort;
  a.velocity_limit = velocity_limit;
  a.lookup = to_lookup(lookup);
  a.delay = to_int(delay, "delay", 0, kMaxActuatorDelay);
  a.integration = to_actuator_integration(integration);
  return a;
}

inline SimulationOptions make_options(double dt, py::handle solver, py::handle position_iterations,
                                      py::handle velocity_iterations,
                                      py::handle compat = py::none()) {
  SimulationOptions o;
  o.dt = dt;
  if (!compat.is_none()) o.compat = to_compat(compat);
  o.solver = to_solver(solver);
  o.position_iterations = to_int(position_iterations, "position_iterations", 1);
  o.velocity_iterations = to_int(velocity_iterations, "velocity_iterations", 0);
  validate_options(o);
  return o;
}

inline NameOrIndex joint_arg(py::handle joint) {
  return to_name_or_index(joint, "joint", "a joint name (str) or a dof index (int)");
}

inline NameOrIndex link_arg(py::handle link) {
  return to_name_or_index(link, "link", "a link name (str) or a link index (int)");
}

inline int index_in(long long index, int size, const char* what) {
  if (index < 0 || index >= size)
    throw std::invalid_argument(std::string(what) + " " + std::to_string(index) +
                                " is out of range [0, " + std::to_string(size) + ")");
  return static_cast<int>(index);
}

/// The dof of a joint given by name (its first dof; a spherical joint's axes by their own names)
/// or by dof index.
inline int dof_of(const Model& model, const NameOrIndex& joint) {
  if (!joint.named) return index_in(joint.index, model.nv, "dof index");
  const int dof = model.dof_index(joint.name);
  const Link& link = model.links[static_cast<size_t>(model.dof_link[static_cast<size_t>(dof)])];
  if (link.joint_type == JointType::spherical && link.joint_name == joint.name)
    throw std::invalid_argument("joint '" + joint.name + "' is spherical: name one of its axes, '" +
                                joint.name + ":twist', '" + joint.name + ":swing1' or '" +
                                joint.name + ":swing2'");
  return dof;
}

inline int link_of(const Model& model, const NameOrIndex& link) {
  return link.named ? model.link_index(link.name)
                    : index_in(link.index, model.num_links(), "link index");
}

/// A link (by name or index) or a merged link's frame (by name) for the frame queries.
inline NamedFrame frame_of(const Model& model, const NameOrIndex& link) {
  if (link.named) return model.frame(link.name);
  NamedFrame f;
  f.link = index_in(link.index, model.num_links(), "link index");
  f.name = model.links[static_cast<size_t>(f.link)].name;
  return f;
}

/// set_link_mass of Batch: a link by name or index, one mass or one per env_ids.
template <class B>
void set_link_mass_of(B& b, py::handle link, py::handle mass, py::handle env_ids, bool scale) {
  const NameOrIndex l = link_arg(link);
  const std::vector<int> ids = to_env_ids(env_ids, b.size());
  const bool scalar = as_float_array(mass, "mass").ndim() == 0;
  const VecX m = to_vector(mass, scalar ? 1 : static_cast<Eigen::Index>(ids.size()), "mass", true);
  locked(b, [&] { b.set_link_mass(ids, link_of(b.model(), l), m, scale); });
}

/// The model of a simulation or batch, read under its lock.
template <class T>
std::shared_ptr<const Model> model_of(const T& object) {
  return locked(object, [&] { return object.model_ptr(); });
}

/// f(dof) under the simulation's lock, for a joint given by name or dof index.
template <class F>
auto on_joint(const Simulation& s, py::handle joint, F f) {
  const NameOrIndex j = joint_arg(joint);
  return locked(s, [&] { return f(dof_of(s.model(), j)); });
}

/// A row kind's field value given by keyword: a real number (a bool or a string is refused with
/// std::invalid_argument naming `what`, the kind and field).
inline double row_field_value(py::handle value, const std::string& what) {
  if (py::isinstance<py::bool_>(value) ||
      !(py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value) ||
        py::hasattr(value, "__float__")))
    throw std::invalid_argument(what + " = " + py::repr(value).cast<std::string>() +
                                " is not a number");
  return value.cast<double>();
}

inline std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr auto ref = py::return_value_policy::reference_internal;

// Docstrings shared by Simulation and Batch.
constexpr const char* kSolverDoc = "'pgs' or 'tgs' (or a SolverType)";

// Simulation(model, ..., stiffness, damping, drive_type): drives on every revolute and prismatic
// dof at construction, so that targets act from the first snippet on (set_drive_gains' rules).
inline void initial_drives(Simulation& s, py::handle stiffness, py::handle damping,
                           py::handle type) {
  const DriveType t = to_drive_type(type);
  if (stiffness.is_none() && damping.is_none()) {
    if (t != DriveType::force)
      throw std::invalid_argument("Simulation: drive_type = '" + std::string(to_string(t)) +
                                  "' needs stiffness or damping");
    return;
  }
  const Model& model = s.model();
  // A scalar goes to the revolute and prismatic dofs only; an (nv,) array as given.
  auto gains = [&](py::handle g, const char* what) -> VecX {
    VecX v = VecX::Zero(model.nv);
    if (g.is_none()) return v;
    if (as_float_array(g, what).ndim() != 0) return to_vector(g, model.nv, what);
    const double value = to_vector(g, 1, what, true)[0];
    for (const Link& l : model.links)
      if (l.joint_type == JointType::revolute || l.joint_type == JointType::prismatic)
        v[l.v_index] = value;
    return v;
  };
  set_drive_gains(s, gains(stiffness, "stiffness"), gains(damping, "damping"), t);
}

}  // namespace featherdrive::python
