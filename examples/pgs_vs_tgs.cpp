// PGS against TGS on a driven slider and a driven 3-link chain: writes the CSV files that
// scripts/pgs_vs_tgs.py turns into docs/math/pgs_vs_tgs_*.png and the error tables of
// docs/math/pgs_vs_tgs.md.
//
//   pgs_vs_tgs OUTPUT_DIR
//
// Every file starts with one comment line "# key=value ..." holding the scene's parameters, then a
// header row. Only the public headers are used.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "featherdrive/algorithm/crba.hpp"
#include "featherdrive/algorithm/rnea.hpp"
#include "featherdrive/model/model_builder.hpp"
#include "featherdrive/sim/simulation.hpp"

using namespace featherdrive;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;
constexpr double kDt = 1.0 / 60.0;
constexpr double kGravity = 9.81;

// Link geometry shared by the scenes (and by the Python script, through the parameter lines).
constexpr double kSliderMass = 1.0;
constexpr double kChainMass = 1.0;
constexpr double kChainLength = 0.5;
constexpr int kChainLinks = 3;

Mat3 box_inertia(double m, double sx, double sy, double sz) {
  return Vec3(m / 12 * (sy * sy + sz * sz), m / 12 * (sx * sx + sz * sz),
              m / 12 * (sx * sx + sy * sy))
      .asDiagonal();
}

// A 1 kg block on a prismatic joint along z; gravity along -z when `gravity_along_axis`, otherwise
// across the axis (then it does nothing to the joint).
std::shared_ptr<const Model> make_slider(bool gravity_along_axis) {
  ModelBuilder b;
  b.set_gravity(gravity_along_axis ? Vec3(0, 0, -kGravity) : Vec3(0, -kGravity, 0));
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), box_inertia(1.0, 0.1, 0.1, 0.1),
                       fixed_joint("world_joint")));
  b.add_link(make_link("slider", "base", kSliderMass, Vec3::Zero(),
                       box_inertia(kSliderMass, 0.1, 0.1, 0.1),
                       prismatic_joint("slide", Vec3::UnitZ())));
  return std::make_shared<const Model>(b.build());
}

// A planar chain hanging from a fixed base: revolute joints about y, uniform rods of mass m and
// length l along -z, centre of mass at mid-length, I_yy = m l^2 / 12.
std::shared_ptr<const Model> make_chain() {
  ModelBuilder b;
  b.set_gravity(Vec3(0, 0, -kGravity));
  b.add_link(make_link("base", "", 1.0, Vec3::Zero(), box_inertia(1.0, 0.1, 0.1, 0.1),
                       fixed_joint("world_joint")));
  std::string parent = "base";
  const double rod = kChainMass * kChainLength * kChainLength / 12.0;
  for (int i = 0; i < kChainLinks; ++i) {
    const std::string name = "link" + std::to_string(i + 1);
    b.add_link(make_link(name, parent, kChainMass, Vec3(0, 0, -kChainLength / 2),
                         Vec3(rod, rod, 1e-4).asDiagonal(),
                         revolute_joint("joint" + std::to_string(i + 1), Vec3::UnitY(),
                                        i == 0 ? Vec3::Zero() : Vec3(0, 0, -kChainLength))));
    parent = name;
  }
  return std::make_shared<const Model>(b.build());
}

struct SolverSetting {
  std::string label;  // column prefix, e.g. "pgs4_1"
  SolverType solver;
  int position_iterations;
  int velocity_iterations;
};

SimulationOptions options_for(const SolverSetting& s) {
  SimulationOptions o;
  o.dt = kDt;
  o.solver = s.solver;
  o.position_iterations = s.position_iterations;
  o.velocity_iterations = s.velocity_iterations;
  return o;
}

class Csv {
 public:
  Csv(const std::filesystem::path& path, const std::string& params) : out_(path), path_(path) {
    if (!out_) throw std::runtime_error("cannot write " + path.string());
    out_ << "# " << params << "\n";
    out_.precision(17);
  }
  void header(const std::vector<std::string>& columns) { row_strings(columns); }
  void row(const std::vector<double>& values) {
    for (size_t i = 0; i < values.size(); ++i) out_ << (i ? "," : "") << values[i];
    out_ << "\n";
  }
  ~Csv() { std::cout << "wrote " << path_.string() << "\n"; }

 private:
  void row_strings(const std::vector<std::string>& values) {
    for (size_t i = 0; i < values.size(); ++i) out_ << (i ? "," : "") << values[i];
    out_ << "\n";
  }
  std::ofstream out_;
  std::filesystem::path path_;
};

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// Target of a scene at the end of the step that ends at time t (what a controller running at the
// step rate would send).
struct Target {
  double position, velocity;
};

// Slider scene: the same gains and target law under several solver settings; one row per step
// with x, v and the reported drive force of each setting.
template <class TargetLaw>
void slider_scene(const std::filesystem::path& path, const std::string& extra_params, double kp,
                  double kd, double duration, const std::vector<SolverSetting>& settings,
                  TargetLaw target) {
  auto model = make_slider(false);
  const int steps = static_cast<int>(std::lround(duration / kDt));
  std::vector<Simulation> sims;
  for (const SolverSetting& s : settings) {
    sims.emplace_back(model, options_for(s));
    sims.back().set_drive("slide", Drive{DriveType::force, kp, kd, kInf, 0.0, 0.0});
  }
  Csv csv(path, "m=" + fmt(kSliderMass) + " kp=" + fmt(kp) + " kd=" + fmt(kd) + " dt=" +
                    fmt(kDt) + " " + extra_params);
  std::vector<std::string> columns{"t", "target_x", "target_v"};
  for (const SolverSetting& s : settings)
    for (const char* q : {"_x", "_v", "_f"}) columns.push_back(s.label + q);
  csv.header(columns);
  std::vector<double> row{0.0, target(0.0).position, target(0.0).velocity};
  for (size_t i = 0; i < settings.size(); ++i) row.insert(row.end(), {0.0, 0.0, 0.0});
  csv.row(row);
  for (int k = 0; k < steps; ++k) {
    const double t_end = (k + 1) * kDt;
    const Target tg = target(t_end);
    row = {t_end, tg.position, tg.velocity};
    for (Simulation& sim : sims) {
      sim.set_drive_target("slide", tg.position, tg.velocity);
      sim.step();
      row.insert(row.end(), {sim.q()[0], sim.qd()[0], sim.drive_force()[0]});
    }
    csv.row(row);
  }
}

// The chain's step response from rest at q = 0 to constant targets, under gravity.
void chain_step_scene(const std::filesystem::path& path, double kp, double kd, const VecX& xT,
                      double duration, const std::vector<SolverSetting>& settings) {
  auto model = make_chain();
  const int n = model->nv;
  const int steps = static_cast<int>(std::lround(duration / kDt));
  std::vector<Simulation> sims;
  for (const SolverSetting& s : settings) {
    sims.emplace_back(model, options_for(s));
    for (int j = 0; j < n; ++j) sims.back().set_drive(j, Drive{DriveType::force, kp, kd, kInf, xT[j], 0.0});
  }
  std::string params = "links=" + std::to_string(n) + " m=" + fmt(kChainMass) + " l=" +
                       fmt(kChainLength) + " g=" + fmt(kGravity) + " kp=" + fmt(kp) + " kd=" +
                       fmt(kd) + " dt=" + fmt(kDt);
  for (int j = 0; j < n; ++j) params += " xT" + std::to_string(j + 1) + "=" + fmt(xT[j]);
  Csv csv(path, params);
  std::vector<std::string> columns{"t"};
  for (const SolverSetting& s : settings)
    for (const char* q : {"_q", "_qd", "_f"})
      for (int j = 0; j < n; ++j) columns.push_back(s.label + q + std::to_string(j + 1));
  csv.header(columns);
  auto append = [&](std::vector<double>& row, const Simulation& sim) {
    for (int j = 0; j < n; ++j) row.push_back(sim.q()[j]);
    for (int j = 0; j < n; ++j) row.push_back(sim.qd()[j]);
    for (int j = 0; j < n; ++j) row.push_back(sim.drive_force()[j]);
  };
  std::vector<double> row{0.0};
  for (const Simulation& sim : sims) append(row, sim);
  csv.row(row);
  for (int k = 0; k < steps; ++k) {
    row = {(k + 1) * kDt};
    for (Simulation& sim : sims) {
      sim.step();
      append(row, sim);
    }
    csv.row(row);
  }
}

// The chain step scene run on until it is at rest (30 s): where each solver rests, against the
// static sag xT - g(q) / kp, and the drive force against g(q) + c(q, qd) (gravity plus the
// velocity-product torques at the reported velocity).
void chain_rest_after_step(const std::filesystem::path& path, double kp, double kd, const VecX& xT,
                           const std::vector<SolverSetting>& settings) {
  auto model = make_chain();
  const int n = model->nv;
  Data data(*model);
  Csv csv(path, "kp=" + fmt(kp) + " kd=" + fmt(kd) + " dt=" + fmt(kDt) + " steps=1800");
  std::vector<std::string> columns{"solver", "position_iterations", "velocity_iterations"};
  for (const char* q : {"q_minus_sag", "qd", "force_minus_gravity_minus_c"})
    for (int j = 0; j < n; ++j) columns.push_back(std::string(q) + std::to_string(j + 1));
  columns.push_back("max_abs_q_change_last_step");
  csv.header(columns);
  for (const SolverSetting& s : settings) {
    Simulation sim(model, options_for(s));
    for (int j = 0; j < n; ++j) sim.set_drive(j, Drive{DriveType::force, kp, kd, kInf, xT[j], 0.0});
    sim.step(1799);
    const VecX before = sim.q();
    sim.step();
    const VecX gravity = rnea(*model, data, sim.q(), VecX::Zero(n), VecX::Zero(n));
    const VecX bias = rnea(*model, data, sim.q(), sim.qd(), VecX::Zero(n));  // c + g
    const VecX sag = xT - gravity / kp;
    std::vector<double> row{s.solver == SolverType::pgs ? 0.0 : 1.0, double(s.position_iterations),
                            double(s.velocity_iterations)};
    for (int j = 0; j < n; ++j) row.push_back(sim.q()[j] - sag[j]);
    for (int j = 0; j < n; ++j) row.push_back(sim.qd()[j]);
    for (int j = 0; j < n; ++j) row.push_back(sim.drive_force()[j] - bias[j]);
    row.push_back((sim.q() - before).cwiseAbs().maxCoeff());
    csv.row(row);
  }
}

// M(q) and g(q) of the chain at a few configurations, for the script to check its own model of it.
void chain_dynamics_check(const std::filesystem::path& path) {
  auto model = make_chain();
  Data data(*model);
  const int n = model->nv;
  Csv csv(path, "links=" + std::to_string(n) + " m=" + fmt(kChainMass) + " l=" + fmt(kChainLength) +
                    " g=" + fmt(kGravity));
  std::vector<std::string> columns;
  for (int j = 0; j < n; ++j) columns.push_back("q" + std::to_string(j + 1));
  for (int j = 0; j < n; ++j) columns.push_back("qd" + std::to_string(j + 1));
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) columns.push_back("M" + std::to_string(r + 1) + std::to_string(c + 1));
  // rnea(q, qd, 0) = c(q, qd) - g(q): the joint forces that hold the chain at zero acceleration.
  for (int j = 0; j < n; ++j) columns.push_back("bias" + std::to_string(j + 1));
  csv.header(columns);
  const double samples[][6] = {{0.3, -0.5, 0.8, 0.0, 0.0, 0.0},
                               {-1.1, 0.4, 2.0, 0.7, -1.3, 0.4},
                               {0.8, -0.6, 0.4, 2.0, 1.0, -3.0}};
  for (const auto& s : samples) {
    VecX q(n), qd(n);
    for (int j = 0; j < n; ++j) {
      q[j] = s[j];
      qd[j] = s[n + j];
    }
    const MatX M = crba(*model, data, q);
    const VecX bias = rnea(*model, data, q, qd, VecX::Zero(n));
    std::vector<double> row(q.data(), q.data() + n);
    row.insert(row.end(), qd.data(), qd.data() + n);
    for (int r = 0; r < n; ++r)
      for (int c = 0; c < n; ++c) row.push_back(M(r, c));
    row.insert(row.end(), bias.data(), bias.data() + n);
    csv.row(row);
  }
}

// Where each solver comes to rest under gravity, and what it reports there.
//  - slider with gravity along its axis, constant target;
//  - the chain at kp from 1e2 to 1e12 with critical damping per dof (32 position iterations).
void rest_scene(const std::filesystem::path& slider_path, const std::filesystem::path& chain_path) {
  {
    auto model = make_slider(true);
    const double kp = 100.0, kd = 20.0, xT = 0.0;
    Csv csv(slider_path, "m=" + fmt(kSliderMass) + " g=" + fmt(kGravity) + " kp=" + fmt(kp) +
                             " kd=" + fmt(kd) + " xT=" + fmt(xT) + " dt=" + fmt(kDt) + " steps=1200");
    csv.header({"solver", "position_iterations", "velocity_iterations", "x", "v", "force",
                "x_change_last_step"});
    for (const SolverSetting& s : {SolverSetting{"pgs", SolverType::pgs, 4, 1},
                                   SolverSetting{"pgs", SolverType::pgs, 4, 0},
                                   SolverSetting{"tgs", SolverType::tgs, 1, 1},
                                   SolverSetting{"tgs", SolverType::tgs, 4, 1},
                                   SolverSetting{"tgs", SolverType::tgs, 16, 1},
                                   SolverSetting{"tgs", SolverType::tgs, 64, 1}}) {
      Simulation sim(model, options_for(s));
      sim.set_drive("slide", Drive{DriveType::force, kp, kd, kInf, xT, 0.0});
      sim.step(1199);
      const double before = sim.q()[0];
      sim.step();
      csv.row({s.solver == SolverType::pgs ? 0.0 : 1.0, double(s.position_iterations),
               double(s.velocity_iterations), sim.q()[0], sim.qd()[0], sim.drive_force()[0],
               sim.q()[0] - before});
    }
  }
  {
    auto model = make_chain();
    const int n = model->nv;
    VecX xT(n);
    xT << 0.8, -0.6, 0.4;
    Data data(*model);
    const MatX Minv = crba(*model, data, xT).inverse();
    Csv csv(chain_path, "links=" + std::to_string(n) + " dt=" + fmt(kDt) +
                            " steps=600 critical damping per dof at the target");
    csv.header({"solver", "position_iterations", "velocity_iterations", "kp",
                "max_abs_q_minus_static_sag", "max_abs_qd", "max_abs_force_minus_gravity",
                "max_abs_q_change_last_step"});
    for (const SolverSetting& s : {SolverSetting{"pgs", SolverType::pgs, 32, 0},
                                   SolverSetting{"pgs", SolverType::pgs, 32, 1},
                                   SolverSetting{"pgs", SolverType::pgs, 128, 0},
                                   SolverSetting{"tgs", SolverType::tgs, 32, 1}}) {
      for (double kp = 1e2; kp <= 1e12 * 1.0001; kp *= 10) {
        Simulation sim(model, options_for(s));
        for (int j = 0; j < n; ++j)
          sim.set_drive(j, Drive{DriveType::force, kp, 2 * std::sqrt(kp / Minv(j, j)), kInf, xT[j], 0.0});
        sim.step(599);
        const VecX before = sim.q();
        sim.step();
        // Static sag: kp (xT - q) = g(q), g(q) = rnea(q, 0, 0) (the torques that hold the chain).
        const VecX gravity = rnea(*model, data, sim.q(), VecX::Zero(n), VecX::Zero(n));
        const VecX sag = xT - gravity / kp;
        csv.row({s.solver == SolverType::pgs ? 0.0 : 1.0, double(s.position_iterations),
                 double(s.velocity_iterations), kp, (sim.q() - sag).cwiseAbs().maxCoeff(),
                 sim.qd().cwiseAbs().maxCoeff(), (sim.drive_force() - gravity).cwiseAbs().maxCoeff(),
                 (sim.q() - before).cwiseAbs().maxCoeff()});
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUTPUT_DIR\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir(argv[1]);
  std::filesystem::create_directories(dir);

  const std::vector<SolverSetting> both{{"pgs4_1", SolverType::pgs, 4, 1},
                                        {"tgs4_1", SolverType::tgs, 4, 1}};
  // Step responses: target 0.1 m from t = 0 on, a lightly damped (zeta = 0.1) soft and stiff drive.
  const auto step_target = [](double) { return Target{0.1, 0.0}; };
  slider_scene(dir / "slider_step_soft.csv", "xT=0.1", 100.0, 2.0, 2.0, both, step_target);
  slider_scene(dir / "slider_step_stiff.csv", "xT=0.1", 1e4, 20.0, 0.5, both, step_target);
  // The chain from rest at q = 0 to xT under gravity.
  VecX xT(kChainLinks);
  xT << 0.8, -0.6, 0.4;
  chain_step_scene(dir / "chain_step.csv", 200.0, 10.0, xT, 3.0, both);
  chain_rest_after_step(dir / "chain_step_rest.csv", 200.0, 10.0, xT,
                        {{"pgs4_1", SolverType::pgs, 4, 1},
                         {"pgs4_0", SolverType::pgs, 4, 0},
                         {"pgs64_0", SolverType::pgs, 64, 0},
                         {"tgs4_1", SolverType::tgs, 4, 1},
                         {"tgs64_1", SolverType::tgs, 64, 1}});
  chain_dynamics_check(dir / "chain_dynamics_check.csv");

  // Sine tracking, the target sampled at the end of each step; TGS also with many sub-steps.
  const std::vector<SolverSetting> sine_settings{{"pgs4_1", SolverType::pgs, 4, 1},
                                                 {"tgs4_1", SolverType::tgs, 4, 1},
                                                 {"pgs64_1", SolverType::pgs, 64, 1},
                                                 {"tgs16_1", SolverType::tgs, 16, 1},
                                                 {"tgs64_1", SolverType::tgs, 64, 1},
                                                 {"tgs1024_1", SolverType::tgs, 1024, 1}};
  const double amplitude = 0.1;
  for (double hz : {0.5, 1.0, 2.0, 4.0}) {
    const double w = 2 * kPi * hz;
    const auto sine = [amplitude, w](double t) {
      return Target{amplitude * std::sin(w * t), amplitude * w * std::cos(w * t)};
    };
    char name[64];
    std::snprintf(name, sizeof name, "slider_sine_%gHz.csv", hz);
    slider_scene(dir / name, "amplitude=" + fmt(amplitude) + " hz=" + fmt(hz), 100.0, 20.0, 6.0,
                 sine_settings, sine);
    // The same samples with the secant velocity (x_T(t) - x_T(t - dt)) / dt as velocity target:
    // TGS's interpolated target then joins the samples into a continuous polyline.
    const auto secant = [amplitude, w](double t) {
      return Target{amplitude * std::sin(w * t),
                    amplitude * (std::sin(w * t) - std::sin(w * (t - kDt))) / kDt};
    };
    std::snprintf(name, sizeof name, "slider_sine_secant_%gHz.csv", hz);
    slider_scene(dir / name, "amplitude=" + fmt(amplitude) + " hz=" + fmt(hz), 100.0, 20.0, 6.0,
                 {sine_settings[0], sine_settings[1], sine_settings[5]}, secant);
  }

  rest_scene(dir / "slider_rest.csv", dir / "chain_rest.csv");
  return 0;
}
