#include "compare_table.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "featherdrive/core/format.hpp"
#include "featherdrive/io/trajectory.hpp"

namespace fs = std::filesystem;
using namespace featherdrive;

void print_difference_table(const TrajectoryComparison& c, const std::string& other) {
  std::printf("  largest |featherdrive - %s| per joint, at step; relative: / the scale below\n",
              other.c_str());
  std::printf("  %-16s %10s %5s %9s  %10s %5s %9s  %10s %5s %9s\n", "joint", "q", "step",
              "relative", "qd", "step", "relative", "force", "step", "relative");
  // Against a scale of 0 (the reference's quantity never leaves 0) any difference is infinite.
  auto rel = [](double v, double scale) {
    return scale > 0.0 ? v / scale : v > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
  };
  for (const JointDifference& j : c.joints)
    std::printf("  %-16s %10.2e %5zu %9.1e  %10.2e %5zu %9.1e  %10.2e %5zu %9.1e\n",
                j.joint.c_str(), j.q.value, j.q.row, rel(j.q.value, c.scale_q), j.qd.value,
                j.qd.row, rel(j.qd.value, c.scale_qd), j.f.value, j.f.row,
                rel(j.f.value, c.scale_f));
  std::printf("  %-16s %10.4g %5s %9s  %10.4g %5s %9s  %10.4g\n", "scale", c.scale_q, "", "",
              c.scale_qd, "", "", c.scale_f);
  std::printf("  (scale: largest |q|, |qd|, |force| of %s's run over all joints and steps%s)\n",
              other.c_str(),
              c.scale_q > 0.0 && c.scale_qd > 0.0 && c.scale_f > 0.0
                  ? ""
                  : "; relative to a scale of 0, any difference is inf");
  std::printf("  largest relative difference: q %.1e, qd %.1e, force %.1e\n", c.relative_q(),
              c.relative_qd(), c.relative_f());
}

void write_differences(const fs::path& path, const JointTrajectory& fd,
                       const JointTrajectory& other) {
  std::ofstream out(path);
  out << "step,t";
  for (const char* prefix : {"dq:", "dqd:", "df:"})
    for (const std::string& j : other.joints) out << ',' << csv_field(prefix + j);
  out << '\n';
  std::vector<size_t> in_fd;  // columns matched by name, as compare_trajectories does
  for (const std::string& j : other.joints)
    in_fd.push_back(
        static_cast<size_t>(std::find(fd.joints.begin(), fd.joints.end(), j) - fd.joints.begin()));
  for (size_t k = 0; k < other.rows(); ++k) {
    out << k << ',' << format_double(other.t[k]);
    for (const auto m : {&JointTrajectory::q, &JointTrajectory::qd, &JointTrajectory::f})
      for (size_t j = 0; j < other.joints.size(); ++j)
        out << ',' << format_double((fd.*m)[k][in_fd[j]] - (other.*m)[k][j]);
    out << '\n';
  }
  if (!out.flush()) throw std::runtime_error("cannot write " + path.string());
}
