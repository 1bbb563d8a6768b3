// libFuzzer: MJCF import from fuzzed XML text (parse_mjcf, through MuJoCo 2.2.2's compiler). Bad
// input must end in InputError (or another std::invalid_argument); a model that imports must
// take its own reference pose, mimic rows, ground and actuators, and simulate a few steps with a
// finite state or a DivergenceError.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "check.hpp"
#include "featherdrive/io/mjcf.hpp"

using namespace featherdrive;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > 20000) return -1;  // keep the inputs small; large ones test TinyXML2 only
  const std::string xml(reinterpret_cast<const char*>(data), size);
  for (bool fixed_base : {true, false}) {
    UrdfOptions options;
    options.fixed_base = fixed_base;
    MjcfRobot robot;
    try {
      robot = parse_mjcf(xml, "fuzz.xml", options);
    } catch (const std::invalid_argument&) {
      continue;
    }
    if (!robot.model) fuzz::bug("parse_mjcf returned no model");
    if (static_cast<int>(robot.dof_order.size()) != robot.model->nv)
      fuzz::bug("dof_order does not list every dof");
    if (robot.q0.size() != robot.model->nq) fuzz::bug("q0 is not a configuration of the model");
    for (const MjcfActuator& a : robot.actuators)
      if (a.actuator.kind != ActuatorKind::none && (a.dof < 0 || a.dof >= robot.model->nv))
        fuzz::bug("a driving actuator without a dof of the model");
    Simulation sim(robot.model);
    // What the reader returns was checked by it: none of these may refuse it.
    try {
      sim.set_q(robot.q0);
      sim.set_mimic_joints(robot.mimic_joints);
      if (robot.ground) sim.set_ground(*robot.ground);
      apply_mjcf_actuators(robot, sim);
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "%s\n", e.what());
      fuzz::bug("the simulation refused what parse_mjcf returned");
    }
    fuzz::check_finite(sim);
    for (int k = 0; k < 3; ++k)
      if (!fuzz::checked_step(sim)) break;
  }
  return 0;
}
