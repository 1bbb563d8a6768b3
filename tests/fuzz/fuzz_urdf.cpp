// libFuzzer: URDF import from fuzzed XML text. Bad input must end in InputError (or another
// std::invalid_argument); a model that imports must simulate a few steps with a finite state or a
// DivergenceError.
#include <cstddef>
#include <cstdint>
#include <string>

#include "check.hpp"
#include "featherdrive/io/urdf.hpp"

using namespace featherdrive;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > 20000) return -1;  // keep the inputs small; large ones test urdfdom's XML parser only
  const std::string xml(reinterpret_cast<const char*>(data), size);
  for (bool fixed_base : {true, false}) {
    UrdfOptions options;
    options.fixed_base = fixed_base;
    UrdfRobot robot;
    try {
      robot = parse_urdf(xml, "fuzz.urdf", options);
    } catch (const std::invalid_argument&) {
      continue;
    }
    if (!robot.model) fuzz::bug("parse_urdf returned no model");
    if (static_cast<int>(robot.dof_order.size()) != robot.model->nv)
      fuzz::bug("dof_order does not list every dof");
    Simulation sim(robot.model);
    for (int k = 0; k < 3; ++k)
      if (!fuzz::checked_step(sim)) break;
  }
  return 0;
}
