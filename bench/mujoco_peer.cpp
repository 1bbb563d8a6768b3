// MuJoCo 2.2.2 on the benchmark robots: MJCF written from our Model (the mapping of
// tests/peers/mujoco_test.cpp: one body per link, nested as in the tree, joint frames as body
// frames, principal inertia), a position actuator (kp) and joint damping (kd) on every revolute
// joint with ctrl = the target, contacts disabled, no limits. With Euler, MuJoCo integrates the
// damping implicitly and the actuator's stiffness explicitly; with the implicit integrator, both.
#include <mujoco/mujoco.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Eigenvalues>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include "peers.hpp"

namespace featherdrive::bench {
namespace {

std::string num(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

std::string nums(std::initializer_list<double> values) {
  std::string out;
  for (double v : values) {
    if (!out.empty()) out += ' ';
    out += num(v);
  }
  return out;
}

void write_body(const Model& model, int i, int depth, std::ostringstream& xml) {
  const Link& link = model.links[i];
  const std::string indent(2 * static_cast<size_t>(depth), ' ');
  const Transform& X = link.tree_transform;
  const Quat rotation(X.E.transpose());
  // Bodies and joints are named by index: a URDF's names may collide with MuJoCo's ("world").
  xml << indent << "<body name=\"b" << i << "\" pos=\"" << nums({X.r.x(), X.r.y(), X.r.z()})
      << "\" quat=\"" << nums({rotation.w(), rotation.x(), rotation.y(), rotation.z()}) << "\">\n";
  Eigen::SelfAdjointEigenSolver<Mat3> eig(link.inertia_com);
  Mat3 axes = eig.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);
  const Quat principal(axes);
  const Vec3 moments = eig.eigenvalues();
  xml << indent << "  <inertial pos=\"" << nums({link.com.x(), link.com.y(), link.com.z()})
      << "\" quat=\"" << nums({principal.w(), principal.x(), principal.y(), principal.z()})
      << "\" mass=\"" << num(link.mass) << "\" diaginertia=\""
      << nums({moments.x(), moments.y(), moments.z()}) << "\"/>\n";
  const Vec3& a = link.axis;
  switch (link.joint_type) {
    case JointType::fixed: break;
    case JointType::revolute:
      xml << indent << "  <joint name=\"j" << i << "\" type=\"hinge\" axis=\""
          << nums({a.x(), a.y(), a.z()}) << "\" damping=\"" << num(kDamping) << "\"/>\n";
      break;
    case JointType::prismatic:
      xml << indent << "  <joint name=\"j" << i << "\" type=\"slide\" axis=\""
          << nums({a.x(), a.y(), a.z()}) << "\"/>\n";
      break;
    case JointType::spherical:
      xml << indent << "  <joint name=\"j" << i << "\" type=\"ball\"/>\n";
      break;
    case JointType::floating:
      xml << indent << "  <joint name=\"j" << i << "\" type=\"free\"/>\n";
      break;
  }
  for (int c : link.children) write_body(model, c, depth + 1, xml);
  xml << indent << "</body>\n";
}

std::string to_mjcf(const Model& model, MujocoIntegrator integrator) {
  std::ostringstream xml;
  const Vec3& g = model.gravity;
  xml << "<mujoco model=\"featherdrive_bench\">\n"
      << "  <compiler angle=\"radian\"/>\n"
      << "  <option timestep=\"" << num(kDt) << "\" gravity=\"" << nums({g.x(), g.y(), g.z()})
      << "\" integrator=\"" << (integrator == MujocoIntegrator::euler ? "Euler" : "implicit")
      << "\">\n"
      << "    <flag contact=\"disable\"/>\n"
      << "  </option>\n"
      << "  <worldbody>\n";
  write_body(model, 0, 2, xml);
  xml << "  </worldbody>\n  <actuator>\n";
  for (int i = 0; i < model.num_links(); ++i)
    if (model.links[i].joint_type == JointType::revolute)
      xml << "    <position joint=\"j" << i << "\" kp=\"" << num(kStiffness)
          << "\"/>\n";
  xml << "  </actuator>\n</mujoco>\n";
  return xml.str();
}

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};

std::unique_ptr<mjModel, MjModelDeleter> load_mjcf(const std::string& xml) {
  namespace fs = std::filesystem;
  static int counter = 0;
  const fs::path dir = fs::temp_directory_path() / ("featherdrive_bench_" +
                                                    std::to_string(::getpid()) + "_" +
                                                    std::to_string(counter++));
  fs::create_directories(dir);
  const fs::path file = dir / "model.xml";
  {
    std::ofstream out(file);
    out << xml;
  }
  std::array<char, 1000> error{};
  std::unique_ptr<mjModel, MjModelDeleter> m(
      mj_loadXML(file.c_str(), nullptr, error.data(), static_cast<int>(error.size())));
  std::error_code ignored;
  fs::remove_all(dir, ignored);
  if (!m) throw std::runtime_error(std::string("mj_loadXML: ") + error.data());
  return m;
}

}  // namespace

void mujoco_step(benchmark::State& state, const BenchRobot& robot, MujocoIntegrator integrator) {
  const Model& model = *robot.model;
  std::unique_ptr<mjModel, MjModelDeleter> m;
  try {
    m = load_mjcf(to_mjcf(model, integrator));
  } catch (const std::exception& e) {
    // MuJoCo 2.2.2's XML parser stops at 100 levels of element nesting (chains of 256 links
    // and more cannot be written as MJCF for it).
    state.SkipWithError(e.what());
    return;
  }
  if (m->nq != model.nq || m->nv != model.nv) {
    state.SkipWithError("MuJoCo's model has other dimensions than ours");
    return;
  }
  std::unique_ptr<mjData, MjDataDeleter> d(mj_makeData(m.get()));
  // Actuators are written in link order, so actuator k drives the k-th revolute dof.
  int u = 0;
  for (int dof = 0; dof < model.nv; ++dof)
    if (is_driven(model, dof)) d->ctrl[u++] = robot.target[dof];
  auto reset = [&] {
    for (int k = 0; k < model.nq; ++k) d->qpos[k] = robot.q0[k];
    for (int k = 0; k < model.nv; ++k) d->qvel[k] = 0.0;
  };
  reset();
  auto finite = [&] {
    for (int k = 0; k < model.nv; ++k)
      if (!std::isfinite(d->qvel[k])) return false;
    return true;
  };
  int since_reset = 0;
  long diverged = 0;
  for (auto _ : state) {
    mj_step(m.get(), d.get());
    if (++since_reset == kResetInterval) {
      if (!finite()) ++diverged;
      reset();
      since_reset = 0;
    }
  }
  state.counters["dofs"] = model.nv;
  state.counters["links"] = model.num_links();
  state.counters["diverged"] = static_cast<double>(diverged);
}

void mujoco_batch(benchmark::State& state, const BenchRobot& robot, const std::string& xml,
                  int count, int threads) {
  const Model& model = *robot.model;
  std::unique_ptr<mjModel, MjModelDeleter> m;
  try {
    m = load_mjcf(xml.empty() ? to_mjcf(model, MujocoIntegrator::euler) : xml);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  m->opt.disableflags |= mjDSBL_CONTACT;  // as to_mjcf's (the humanoid's feet are off the floor)
  std::vector<std::unique_ptr<mjData, MjDataDeleter>> data;
  for (int i = 0; i < count; ++i) {
    data.emplace_back(mj_makeData(m.get()));
    mjData* d = data.back().get();
    if (!xml.empty()) continue;  // its own initial state and actuators, ctrl 0
    int u = 0;
    for (int dof = 0; dof < model.nv; ++dof)
      if (is_driven(model, dof)) d->ctrl[u++] = robot.target[dof];
    for (int k = 0; k < model.nq; ++k) d->qpos[k] = robot.q0[k];
  }
  tbb::task_arena arena(threads);
  for (auto _ : state)
    arena.execute([&] {
      tbb::parallel_for(0, count,
                        [&](int i) { mj_step(m.get(), data[static_cast<size_t>(i)].get()); });
    });
  state.counters["env_steps_per_second"] = benchmark::Counter(
      static_cast<double>(count), benchmark::Counter::kIsIterationInvariantRate);
}

void mujoco_batch_from(benchmark::State& state, const std::string& xml, const VecX& qpos0,
                       const VecX& ctrl, int count, int threads) {
  std::unique_ptr<mjModel, MjModelDeleter> m;
  try {
    m = load_mjcf(xml);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  if (qpos0.size() != m->nq || ctrl.size() != m->nu) {
    state.SkipWithError("mujoco_batch_from: qpos0 or ctrl does not fit the model");
    return;
  }
  std::vector<std::unique_ptr<mjData, MjDataDeleter>> data;
  auto reset = [&](mjData* d) {
    mj_resetData(m.get(), d);
    std::copy(qpos0.data(), qpos0.data() + m->nq, d->qpos);
    std::copy(ctrl.data(), ctrl.data() + m->nu, d->ctrl);
  };
  for (int i = 0; i < count; ++i) {
    data.emplace_back(mj_makeData(m.get()));
    reset(data.back().get());
  }
  tbb::task_arena arena(threads);
  long steps = 0;
  for (auto _ : state) {
    arena.execute([&] {
      tbb::parallel_for(0, count,
                        [&](int i) { mj_step(m.get(), data[static_cast<size_t>(i)].get()); });
    });
    if (++steps % kResetInterval == 0) {
      state.PauseTiming();
      for (auto& d : data) reset(d.get());
      state.ResumeTiming();
    }
  }
  state.counters["env_steps_per_second"] = benchmark::Counter(
      static_cast<double>(count), benchmark::Counter::kIsIterationInvariantRate);
}

}  // namespace featherdrive::bench
