#include "featherdrive/io/physx_runner.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>

#include "featherdrive/model/dof_position.hpp"

extern char** environ;

namespace featherdrive {
namespace fs = std::filesystem;
namespace {

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::string cell;
  std::stringstream s(line);
  while (std::getline(s, cell, sep)) out.push_back(cell);
  if (!line.empty() && line.back() == sep) out.emplace_back();
  return out;
}

// The next record of an RFC 4180 CSV at `pos`: a quoted field may hold commas, doubled quotes
// and line breaks (joint names may). `line` counts the lines passed. False at the end.
bool next_record(const std::string& text, size_t& pos, long& line, std::vector<std::string>& cells,
                 const std::string& name) {
  cells.clear();
  if (pos >= text.size()) return false;
  const long first_line = line;
  std::string cell;
  bool quoted = false;
  while (pos < text.size()) {
    const char c = text[pos++];
    if (quoted) {
      if (c != '"') {
        line += c == '\n';
        cell += c;
      } else if (pos < text.size() && text[pos] == '"') {
        cell += '"';
        ++pos;
      } else {
        quoted = false;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.push_back(std::move(cell));
      cell.clear();
    } else if (c == '\n') {
      ++line;
      break;
    } else if (c != '\r' || (pos < text.size() && text[pos] != '\n')) {
      cell += c;
    }
  }
  if (quoted)
    throw PhysxError(name + ": line " + std::to_string(first_line) +
                     ": a quoted field is not closed");
  cells.push_back(std::move(cell));
  return true;
}

int find_column(const std::vector<std::string>& header, const std::string& name) {
  const auto it = std::find(header.begin(), header.end(), name);
  return it == header.end() ? -1 : static_cast<int>(it - header.begin());
}

bool is_file(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

std::string last_line(const fs::path& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return last;
}

}  // namespace

JointTrajectory parse_joint_csv(const std::string& text, const std::string& name) {
  size_t pos = 0;
  long line_no = 1;
  std::vector<std::string> header, cells;
  if (!next_record(text, pos, line_no, header, name))
    throw PhysxError(name + ": empty file, expected a CSV header");
  JointTrajectory t;
  std::vector<int> q_col, qd_col, f_col;
  for (const std::string& h : header) {
    if (h.rfind("q:", 0) != 0) continue;
    const std::string joint = h.substr(2);
    const int qd = find_column(header, "qd:" + joint), f = find_column(header, "f:" + joint);
    // A floating root's q columns (q:<root>:x, ...) have no qd/f of the same name: not a joint.
    if (qd < 0 && f < 0) continue;
    if (qd < 0 || f < 0)
      throw PhysxError(name + ": header: column '" + (qd < 0 ? "qd:" : "f:") + joint +
                       "' is missing for joint '" + joint + "'");
    t.joints.push_back(joint);
    q_col.push_back(find_column(header, h));
    qd_col.push_back(qd);
    f_col.push_back(f);
  }
  const int t_col = find_column(header, "t");
  if (t_col < 0) throw PhysxError(name + ": header: column 't' is missing");
  std::vector<int> root_col;
  for (const char* c : {"px", "py", "pz", "qw", "qx", "qy", "qz", "wx", "wy", "wz", "vx", "vy", "vz"}) {
    const int col = find_column(header, std::string("root:") + c);
    if (col >= 0) root_col.push_back(col);
  }
  if (root_col.size() != 13) root_col.clear();
  // contact:<link>:fx, :fy, :fz (a link name may hold colons: the suffix decides).
  std::vector<std::array<int, 3>> contact_col;
  for (const std::string& h : header) {
    constexpr std::string_view prefix = "contact:", suffix = ":fx";
    if (h.size() < prefix.size() + suffix.size() || h.rfind(prefix, 0) != 0 ||
        h.compare(h.size() - suffix.size(), suffix.size(), suffix) != 0)
      continue;
    const std::string link = h.substr(prefix.size(), h.size() - prefix.size() - suffix.size());
    std::array<int, 3> cols{};
    for (int c = 0; c < 3; ++c) {
      const std::string column = "contact:" + link + ":" + "f" + "xyz"[c];
      cols[static_cast<size_t>(c)] = find_column(header, column);
      if (cols[static_cast<size_t>(c)] < 0)
        throw PhysxError(name + ": header: column '" + column + "' is missing for link '" +
                         link + "'");
    }
    t.contact_links.push_back(link);
    contact_col.push_back(cols);
  }
  const size_t n = t.joints.size();
  for (long row_line = line_no; next_record(text, pos, line_no, cells, name); row_line = line_no) {
    if (cells.size() == 1 && cells[0].empty()) continue;  // a blank line
    if (cells.size() < header.size())
      throw PhysxError(name + ": line " + std::to_string(row_line) + ": " +
                       std::to_string(cells.size()) + " values, the header has " +
                       std::to_string(header.size()));
    auto value = [&](int col) {
      const std::string& c = cells[static_cast<size_t>(col)];
      double v = 0.0;
      const auto [end, ec] = std::from_chars(c.data(), c.data() + c.size(), v);
      if (ec != std::errc() || end != c.data() + c.size() || c.empty())
        throw PhysxError(name + ": line " + std::to_string(row_line) + ", column '" +
                         header[static_cast<size_t>(col)] + "': '" + c + "' is not a number");
      return v;
    };
    t.t.push_back(value(t_col));
    std::vector<double> q(n), qd(n), f(n);
    for (size_t j = 0; j < n; ++j) {
      q[j] = value(q_col[j]);
      qd[j] = value(qd_col[j]);
      f[j] = value(f_col[j]);
    }
    t.q.push_back(std::move(q));
    t.qd.push_back(std::move(qd));
    t.f.push_back(std::move(f));
    if (!root_col.empty()) {
      std::vector<double> root;
      for (int col : root_col) root.push_back(value(col));
      t.root.push_back(std::move(root));
    }
    if (!contact_col.empty()) {
      std::vector<Vec3> force;
      for (const auto& cols : contact_col)
        force.emplace_back(value(cols[0]), value(cols[1]), value(cols[2]));
      t.contact_force.push_back(std::move(force));
    }
  }
  return t;
}

JointTrajectory read_joint_csv(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw PhysxError(path.string() + ": cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_joint_csv(text.str(), path.string());
}

double physx_joint_force(const Simulation& sim, int dof) {
  return sim.drive_force()[dof] + sim.limit_force()[dof] + sim.friction_force()[dof] +
         sim.velocity_limit_force()[dof];
}

JointTrajectory empty_trajectory(const Model& model) {
  JointTrajectory t;
  for (const Link& l : model.links) {
    if (l.nv == 1) t.joints.push_back(l.joint_name);
    if (l.joint_type == JointType::spherical)  // per axis, as PhysX reports them
      for (int k = 0; k < 3; ++k) t.joints.push_back(model.dof_names[l.v_index + k]);
  }
  return t;
}

void append_state(JointTrajectory& out, const Simulation& sim) {
  const Model& model = sim.model();
  const size_t n = out.joints.size();
  std::vector<double> q(n), qd(n), f(n);
  for (size_t j = 0; j < n; ++j) {
    const int dof = model.dof_index(out.joints[j]);
    if (!has_dof_position(model, dof))
      throw std::invalid_argument("joint '" + out.joints[j] + "' has " +
                                  std::to_string(model.links[model.dof_link[dof]].nv) +
                                  " dofs; PhysX's columns are 1-dof joints and spherical axes");
    q[j] = dof_position(model, sim.q(), dof);  // a spherical axis: PhysX's position
    qd[j] = sim.qd()[dof];
    f[j] = physx_joint_force(sim, dof);
  }
  out.t.push_back(sim.time());
  out.q.push_back(std::move(q));
  out.qd.push_back(std::move(qd));
  out.f.push_back(std::move(f));
  if (out.contact_links.empty()) return;
  std::vector<Vec3> force;
  for (const std::string& link : out.contact_links)
    force.push_back(sim.link_contact_force()[static_cast<size_t>(model.link_index(link))]);
  out.contact_force.push_back(std::move(force));
}

std::vector<std::string> physx_contact_links(const Simulation& sim) {
  std::vector<std::string> links;
  if (!sim.ground().enabled) return links;
  for (const CollisionShape& shape : sim.model().shapes) {  // sorted by link
    const std::string& name = sim.model().links[static_cast<size_t>(shape.link)].name;
    if (links.empty() || links.back() != name) links.push_back(name);
  }
  return links;
}

std::string physx_install_hint() {
  return "install node and npm (Debian: apt-get install -y nodejs npm), then the pinned PhysX "
         "package with `make physx` (runs tests/physx/install.sh build/physx)";
}

PhysxInstall find_physx(const std::vector<fs::path>& default_dirs) {
  PhysxInstall out;
  const char* path_env = std::getenv("PATH");
  for (const std::string& dir : split(path_env ? path_env : "", ':')) {
    const fs::path node = fs::path(dir.empty() ? "." : dir) / "node";
    if (is_file(node) && ::access(node.c_str(), X_OK) == 0) {
      out.node = node.string();
      break;
    }
  }
  if (out.node.empty()) {
    std::string m = "node (Node.js 18 or newer) is not on PATH; compare-physx runs PhysX in it: ";
    m += physx_install_hint();
    throw PhysxError(m);
  }
  // What a folder lacks of an install, or "" when it has everything.
  auto missing = [](const fs::path& dir) -> std::string {
    if (!is_file(dir / "harness.js")) return "harness.js";
    const fs::path pkg = dir / "node_modules" / "physx-js-webidl";
    for (const char* f : {"physx-js-webidl.mjs", "physx-js-webidl.wasm"})
      if (!is_file(pkg / f)) return "node_modules/physx-js-webidl";
    return "";
  };
  if (const char* env = std::getenv("FEATHERDRIVE_PHYSX_DIR"); env && *env) {
    out.dir = env;
    const std::string lack = missing(out.dir);
    if (lack.empty()) return out;
    std::string m = "FEATHERDRIVE_PHYSX_DIR = ";
    m += out.dir.string();
    m += ": no ";
    m += lack;
    m += " there; install the PhysX harness into it with `tests/physx/install.sh ";
    m += out.dir.string();
    m += "` (needs node and npm: apt-get install -y nodejs npm), or unset it to use the folder "
         "`make physx` installs into";
    throw PhysxError(m);
  }
  std::string looked;
  for (const fs::path& dir : default_dirs) {
    if (missing(dir).empty()) {
      out.dir = dir;
      return out;
    }
    looked += looked.empty() ? "" : ", ";
    looked += dir.string();
  }
  std::string m = "the PhysX package physx-js-webidl is not installed (looked in ";
  m += looked.empty() ? "no folder" : looked;
  m += "): ";
  m += physx_install_hint();
  m += ", or set FEATHERDRIVE_PHYSX_DIR to a folder tests/physx/install.sh installed into";
  throw PhysxError(m);
}

int run_program(const std::vector<std::string>& argv, const fs::path& stderr_path) {
  if (argv.empty()) return -1;
  std::vector<std::string> args = argv;
  std::vector<char*> ptrs;
  for (std::string& a : args) ptrs.push_back(a.data());
  ptrs.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!stderr_path.empty())
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, stderr_path.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int spawned = posix_spawnp(&pid, args[0].c_str(), &actions, nullptr, ptrs.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

namespace {
// One run on the harness's server (`node harness.js --serve SOCKET`, which the tests start once so
// that PhysX is loaded once, not once per case): the exit status, its messages written to `log`;
// -1 when no server answers on `socket_path` (the caller then starts node itself).
int run_on_server(const std::string& socket_path, const fs::path& scene, const fs::path& csv,
                  const fs::path& log) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  if (socket_path.size() >= sizeof address.sun_path) return -1;
  std::copy(socket_path.begin(), socket_path.end(), address.sun_path);
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    ::close(fd);
    return -1;
  }
  const std::string request = scene.string() + "\t" + csv.string() + "\n";
  bool sent = true;
  for (size_t done = 0; sent && done < request.size();) {
    const ssize_t n = ::send(fd, request.data() + done, request.size() - done, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    sent = n > 0;
    if (sent) done += static_cast<size_t>(n);
  }
  std::string answer;
  char buffer[4096];
  for (ssize_t n; sent && (n = ::read(fd, buffer, sizeof buffer)) != 0;) {
    if (n < 0) {
      if (errno == EINTR) continue;
      break;
    }
    answer.append(buffer, static_cast<size_t>(n));
  }
  ::close(fd);
  const size_t end = answer.find('\n');
  int code = -1;
  if (end == std::string::npos ||
      std::from_chars(answer.data(), answer.data() + end, code).ec != std::errc())
    return -1;
  std::ofstream(log) << answer.substr(end + 1);
  return code;
}
}  // namespace

JointTrajectory run_physx(const PhysxInstall& physx, const Simulation& sim, int steps,
                          const std::vector<TargetsByJoint>& targets,
                          const std::vector<ForcesByJoint>& forces) {
  // Throws for what PhysX lacks.
  const std::string json = physx_scene_json(sim, steps, targets, forces);
  std::string tmpl = (fs::temp_directory_path() / "featherdrive-physx-XXXXXX").string();
  if (::mkdtemp(tmpl.data()) == nullptr) throw PhysxError("cannot make a temporary folder " + tmpl);
  const fs::path dir = tmpl;
  const fs::path scene = dir / "scene.json", csv = dir / "physx.csv", log = dir / "stderr.txt";
  {
    std::ofstream out(scene);
    out << json;
    if (!out.flush()) throw PhysxError("cannot write " + scene.string());
  }
  const std::string harness = (physx.dir / "harness.js").string();
  const char* server = std::getenv("FEATHERDRIVE_PHYSX_SERVER");
  int rc = server && *server ? run_on_server(server, scene, csv, log) : -1;
  if (rc < 0) rc = run_program({physx.node, harness, scene.string(), csv.string()}, log);
  if (rc != 0) {
    std::string m = "PhysX harness ";
    m += rc < 0 ? "could not be run" : "failed (exit " + std::to_string(rc) + ")";
    m += ": ";
    m += physx.node + " " + harness + " " + scene.string() + " " + csv.string();
    const std::string why = last_line(log);
    if (!why.empty()) m += ": " + why;
    throw PhysxError(m, rc);
  }
  JointTrajectory t = read_joint_csv(csv);
  if (t.rows() != static_cast<size_t>(steps) + 1)
    throw PhysxError(csv.string() + ": " + std::to_string(t.rows()) + " rows, expected " +
                     std::to_string(steps + 1) + " (the initial state and " +
                     std::to_string(steps) + " steps)");
  std::error_code ec;
  fs::remove_all(dir, ec);
  return t;
}

namespace {
double relative(const std::vector<JointDifference>& joints, LargestDifference JointDifference::*m,
                double scale) {
  double worst = 0.0;
  for (const JointDifference& j : joints) worst = std::max(worst, (j.*m).value);
  // A difference where the reference never leaves 0 has no finite relative size: infinite.
  if (!(scale > 0.0)) return worst > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
  return worst / scale;
}
}  // namespace

double TrajectoryComparison::relative_q() const {
  return relative(joints, &JointDifference::q, scale_q);
}
double TrajectoryComparison::relative_qd() const {
  return relative(joints, &JointDifference::qd, scale_qd);
}
double TrajectoryComparison::relative_f() const {
  return relative(joints, &JointDifference::f, scale_f);
}

ContactComparison compare_contact_forces(const JointTrajectory& a, const JointTrajectory& reference,
                                         const Vec3& normal) {
  if (a.contact_force.size() != reference.contact_force.size())
    throw PhysxError("the contact forces have " + std::to_string(a.contact_force.size()) +
                     " and " + std::to_string(reference.contact_force.size()) + " rows");
  ContactComparison c;
  for (size_t l = 0; l < reference.contact_links.size(); ++l) {
    const std::string& name = reference.contact_links[l];
    const auto it = std::find(a.contact_links.begin(), a.contact_links.end(), name);
    if (it == a.contact_links.end())
      throw PhysxError("link '" + name + "' has contact forces in one trajectory only");
    const size_t la = static_cast<size_t>(it - a.contact_links.begin());
    LargestDifference d;
    for (size_t k = 0; k < reference.contact_force.size(); ++k) {
      const double ref = normal.dot(reference.contact_force[k][l]);
      double diff = std::abs(normal.dot(a.contact_force[k][la]) - ref);
      if (std::isnan(diff)) diff = std::numeric_limits<double>::infinity();
      if (diff > d.value) d = {diff, k};
      c.scale = std::max(c.scale, std::abs(ref));
    }
    c.links.emplace_back(name, d);
  }
  return c;
}

TrajectoryComparison compare_trajectories(const JointTrajectory& a,
                                          const JointTrajectory& reference) {
  if (a.rows() != reference.rows())
    throw PhysxError("the trajectories have " + std::to_string(a.rows()) + " and " +
                     std::to_string(reference.rows()) + " rows");
  TrajectoryComparison c;
  for (size_t j = 0; j < reference.joints.size(); ++j) {
    const std::string& name = reference.joints[j];
    const auto it = std::find(a.joints.begin(), a.joints.end(), name);
    if (it == a.joints.end()) throw PhysxError("joint '" + name + "' is in one trajectory only");
    const size_t ja = static_cast<size_t>(it - a.joints.begin());
    JointDifference d{name, {}, {}, {}};
    auto fold = [](LargestDifference& l, double x, double y, size_t row) {
      double diff = std::abs(x - y);
      if (std::isnan(diff)) diff = std::numeric_limits<double>::infinity();  // a NaN is the worst
      if (diff > l.value) l = {diff, row};
    };
    for (size_t k = 0; k < reference.rows(); ++k) {
      fold(d.q, a.q[k][ja], reference.q[k][j], k);
      fold(d.qd, a.qd[k][ja], reference.qd[k][j], k);
      fold(d.f, a.f[k][ja], reference.f[k][j], k);
      c.scale_q = std::max(c.scale_q, std::abs(reference.q[k][j]));
      c.scale_qd = std::max(c.scale_qd, std::abs(reference.qd[k][j]));
      c.scale_f = std::max(c.scale_f, std::abs(reference.f[k][j]));
    }
    c.joints.push_back(std::move(d));
  }
  return c;
}

}  // namespace featherdrive
