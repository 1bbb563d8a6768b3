#include "featherdrive/io/checkpoint.hpp"
#include "featherdrive/io/files.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "featherdrive/core/format.hpp"

namespace featherdrive {
namespace {

constexpr char kMagic[8] = {'F', 'D', 'C', 'K', 'P', 'T', '\r', '\n'};
constexpr size_t kHeaderSize = 8 + 4 + 8 + 4 + 4 + 8;

std::uint64_t fnv1a(const char* data, size_t size) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (size_t i = 0; i < size; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::string hex(std::uint64_t v) {
  std::ostringstream s;
  s << "0x" << std::hex << v;
  return s.str();
}

// Little-endian writer.
class Writer {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void u64(std::uint64_t v) {
    for (int i = 0; i < 8; ++i) u8(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
  void vec(const VecX& v) {
    for (Eigen::Index i = 0; i < v.size(); ++i) f64(v[i]);
  }
  void bytes(const char* data, size_t size) { out_.append(data, size); }
  void text(const std::string& s) {
    u64(s.size());
    out_ += s;
  }
  std::string& str() { return out_; }

 private:
  std::string out_;
};

// Little-endian reader over a payload whose size has already been checked; reading past the end
// still throws rather than reading out of bounds.
class ByteReader {
 public:
  ByteReader(const std::string& data, size_t begin, size_t end, const std::string& name)
      : data_(data), pos_(begin), end_(end), name_(name) {}
  std::uint8_t u8() {
    need(1);
    return static_cast<std::uint8_t>(data_[pos_++]);
  }
  std::uint32_t u32() {
    std::uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(u8()) << (8 * i);
    return v;
  }
  std::uint64_t u64() {
    std::uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(u8()) << (8 * i);
    return v;
  }
  std::int64_t i64() { return static_cast<std::int64_t>(u64()); }
  double f64() { return std::bit_cast<double>(u64()); }
  std::string text() {
    const std::uint64_t n = u64();
    need(n);
    std::string out = data_.substr(pos_, n);
    pos_ += n;
    return out;
  }
  VecX vec(int n) {
    VecX v(n);
    for (int i = 0; i < n; ++i) v[i] = f64();
    return v;
  }
  size_t pos() const { return pos_; }

 private:
  void need(size_t n) {
    if (end_ - pos_ < n)
      throw CheckpointError(name_ + ": corrupt checkpoint: the payload ends early at byte " +
                            std::to_string(pos_));
  }
  const std::string& data_;
  size_t pos_, end_;
  const std::string& name_;
};

void hash_double(Writer& w, double v) { w.f64(v); }

[[noreturn]] void fail_checkpoint(const std::string& name, const std::string& why) {
  throw CheckpointError(name + ": " + why);
}

// Version 3: per dof the explicit actuator and its delay history, then the actuator forces.
void write_actuators(Writer& p, const Settings& settings, const State& state) {
  for (size_t d = 0; d < settings.actuators.size(); ++d) {
    const ExplicitActuator& a = settings.actuators[d];
    p.u8(static_cast<std::uint8_t>(a.kind));
    if (a.kind == ActuatorKind::none) continue;
    p.u8(static_cast<std::uint8_t>(a.integration));  // version 6
    for (double v : {a.stiffness, a.damping, a.effort_limit, a.saturation_effort, a.velocity_limit})
      p.f64(v);
    p.i64(a.delay);
    p.u64(a.lookup.size());
    for (const auto& [position, effort] : a.lookup) p.f64(position), p.f64(effort);
    p.f64(settings.actuator_feedforward[static_cast<Eigen::Index>(d)]);
    p.i64(state.actuator_history[d].pushes);
    for (const ActuatorCommand& c : state.actuator_history[d].ring)
      p.f64(c.position), p.f64(c.velocity), p.f64(c.effort);
  }
  p.vec(state.actuator_force);
}

void read_actuators(ByteReader& r, Settings& settings, State& state, const std::string& name,
                    std::uint32_t version) {
  const int nv = static_cast<int>(settings.actuators.size());
  for (int d = 0; d < nv; ++d) {
    ExplicitActuator a;
    const std::uint8_t kind = r.u8();
    if (kind > static_cast<std::uint8_t>(ActuatorKind::remotized_pd))
      fail_checkpoint(name, "corrupt checkpoint: actuator kind " + std::to_string(kind) +
                                " of dof " + std::to_string(d));
    a.kind = static_cast<ActuatorKind>(kind);
    if (a.kind == ActuatorKind::none) continue;  // cleared before the settings were read
    if (version >= 6) {  // before it, every actuator was explicit
      const std::uint8_t integration = r.u8();
      if (integration > static_cast<std::uint8_t>(ActuatorIntegration::implicit_law))
        fail_checkpoint(name, "corrupt checkpoint: actuator integration " +
                                  std::to_string(integration) + " of dof " + std::to_string(d));
      a.integration = static_cast<ActuatorIntegration>(integration);
    }
    a.stiffness = r.f64();
    a.damping = r.f64();
    a.effort_limit = r.f64();
    a.saturation_effort = r.f64();
    a.velocity_limit = r.f64();
    const std::int64_t delay = r.i64();
    if (delay < 0 || delay > kMaxActuatorDelay)
      fail_checkpoint(name, "corrupt checkpoint: actuator delay " + std::to_string(delay) +
                                " of dof " + std::to_string(d) + " is outside [0, " +
                                std::to_string(kMaxActuatorDelay) + "]");
    a.delay = static_cast<int>(delay);
    // Read pair by pair: a forged size runs into the payload's end, not into a huge allocation.
    for (std::uint64_t i = 0, n = r.u64(); i < n; ++i) {
      const double position = r.f64();
      a.lookup.emplace_back(position, r.f64());
    }
    settings.actuators[static_cast<size_t>(d)] = a;
    settings.actuator_feedforward[d] = r.f64();
    DelayHistory<ActuatorCommand>& history = state.actuator_history[static_cast<size_t>(d)];
    history.pushes = static_cast<long>(r.i64());
    history.ring.resize(static_cast<size_t>(a.delay) + 1);
    for (ActuatorCommand& c : history.ring) c = {r.f64(), r.f64(), r.f64()};
  }
  state.actuator_force = r.vec(nv);
}

// Version 4: per dof the implicit drive's delay and, if any, its pushes and ring of delay + 1
// targets.
void write_drive_delays(Writer& p, const Settings& settings, const State& state) {
  for (size_t d = 0; d < settings.drive_delay.size(); ++d) {
    p.i64(settings.drive_delay[d]);
    if (settings.drive_delay[d] == 0) continue;
    p.i64(state.drive_delay_history[d].pushes);
    for (const DriveTarget& t : state.drive_delay_history[d].ring)
      p.f64(t.position), p.f64(t.velocity);
  }
}

void read_drive_delays(ByteReader& r, Settings& settings, State& state, const std::string& name) {
  for (size_t d = 0; d < settings.drive_delay.size(); ++d) {
    const std::int64_t delay = r.i64();
    if (delay < 0 || delay > kMaxDelay)
      fail_checkpoint(name, "corrupt checkpoint: drive delay " + std::to_string(delay) +
                                " of dof " + std::to_string(d) + " is outside [0, " +
                                std::to_string(kMaxDelay) + "]");
    if (delay == 0) continue;  // cleared before the settings were read
    settings.drive_delay[d] = static_cast<int>(delay);
    DelayHistory<DriveTarget>& history = state.drive_delay_history[d];
    history.pushes = static_cast<long>(r.i64());
    history.ring.resize(static_cast<size_t>(delay) + 1);
    for (DriveTarget& t : history.ring) t = {r.f64(), r.f64()};
  }
}

// Version 8: the ground (enabled, height, normal, material), the contact options, and per shape
// the friction anchors kept from the last step (docs/math/contact.md, C9): the contacts' only
// state between steps.
void write_contact_settings(Writer& p, const Settings& settings) {
  const Ground& g = settings.ground;
  p.u8(g.enabled ? 1 : 0);
  for (double v : {g.height, g.normal.x(), g.normal.y(), g.normal.z(), g.material.static_friction,
                   g.material.dynamic_friction, g.material.restitution})
    p.f64(v);
  const ContactOptions& c = settings.contact;
  for (double v : {c.contact_offset, c.rest_offset, c.bounce_threshold}) p.f64(v);
}

void write_friction_anchors(Writer& p, const State& state) {
  for (const FrictionAnchors& a : state.friction_anchors) {
    p.u8(static_cast<std::uint8_t>(a.count));
    for (const Vec3* v : {&a.normal, &a.body[0], &a.body[1], &a.ground[0], &a.ground[1]})
      for (int i = 0; i < 3; ++i) p.f64((*v)[i]);
  }
}

void read_friction_anchors(ByteReader& r, const Model& model, State& state) {
  state.friction_anchors.resize(model.shapes.size());
  for (FrictionAnchors& a : state.friction_anchors) {
    a.count = r.u8();
    for (Vec3* v : {&a.normal, &a.body[0], &a.body[1], &a.ground[0], &a.ground[1]})
      for (int i = 0; i < 3; ++i) (*v)[i] = r.f64();
  }
}

void read_contact_settings(ByteReader& r, Settings& settings) {
  Ground& g = settings.ground;
  g.enabled = r.u8() != 0;
  g.height = r.f64();
  for (int i = 0; i < 3; ++i) g.normal[i] = r.f64();
  g.material.static_friction = r.f64();
  g.material.dynamic_friction = r.f64();
  g.material.restitution = r.f64();
  ContactOptions& c = settings.contact;
  c.contact_offset = r.f64();
  c.rest_offset = r.f64();
  c.bounce_threshold = r.f64();
}

// Version 5: per dof its revolute wrap (1: wrapped), then the mimic joints.
// The row kinds (constraint/row_kinds.hpp), each by name with its fields' names, so that a
// checkpoint reads in a build whose kinds or fields differ: count; per kind its name, its
// fields' count and names, each dof's values (nv x fields) and forces (nv).
void write_row_kinds(Writer& w, const Settings& settings, const State& state) {
  const auto kinds = row_kinds();
  const Eigen::Index nv = settings.row_parameters.rows();
  w.u32(static_cast<std::uint32_t>(kinds.size()));
  for (const RowKindInfo& kind : kinds) {
    w.text(std::string(kind.name));
    w.u32(static_cast<std::uint32_t>(kind.fields.size()));
    for (const RowField& f : kind.fields) w.text(std::string(f.name));
    for (Eigen::Index d = 0; d < nv; ++d)
      for (size_t j = 0; j < kind.fields.size(); ++j)
        w.f64(settings.row_parameters(d, kind.offset + static_cast<Eigen::Index>(j)));
    w.vec(state.row_force.segment(kind.index * nv, nv));
  }
}

// A kind or field this build does not know is refused (its row would be lost); one the checkpoint
// lacks keeps its default.
void read_row_kinds(ByteReader& r, const Model& model, Settings& settings, State& state,
                    const std::string& name) {
  const int nv = model.nv;
  for (const RowKindInfo& kind : row_kinds())
    for (size_t j = 0; j < kind.fields.size(); ++j)
      settings.row_parameters.col(kind.offset + static_cast<Eigen::Index>(j))
          .setConstant(kind.fields[j].default_value);
  const std::uint32_t count = r.u32();
  std::vector<bool> seen(row_kinds().size(), false);
  for (std::uint32_t k = 0; k < count; ++k) {
    const std::string kind_name = r.text();
    const RowKindInfo* kind = nullptr;
    for (const RowKindInfo& known : row_kinds())
      if (known.name == kind_name) kind = &known;
    if (!kind)
      fail_checkpoint(name, "the checkpoint has row kind '" + kind_name +
                                "', which this build does not know (row kinds: " +
                                row_kind_names() + ")");
    if (seen[static_cast<size_t>(kind->index)])
      fail_checkpoint(name, "corrupt checkpoint: row kind '" + kind_name + "' twice");
    seen[static_cast<size_t>(kind->index)] = true;
    const std::uint32_t fields = r.u32();
    if (fields > 1024)
      fail_checkpoint(name, "corrupt checkpoint: row kind '" + kind_name + "' with " +
                                std::to_string(fields) + " fields");
    std::vector<int> column(fields);
    for (std::uint32_t j = 0; j < fields; ++j) {
      const std::string field = r.text();
      column[j] = -1;
      for (size_t f = 0; f < kind->fields.size(); ++f)
        if (kind->fields[f].name == field) column[j] = kind->offset + static_cast<int>(f);
      if (column[j] < 0)
        fail_checkpoint(name, "the checkpoint's row kind '" + kind_name + "' has field '" +
                                  field + "', which this build does not know");
    }
    for (int d = 0; d < nv; ++d)
      for (std::uint32_t j = 0; j < fields; ++j) settings.row_parameters(d, column[j]) = r.f64();
    state.row_force.segment(kind->index * nv, nv) = r.vec(nv);
  }
}

void write_joint_coupling(Writer& p, const Settings& settings) {
  for (const RevoluteWrap wrap : settings.revolute_wrap)
    p.u8(wrap == RevoluteWrap::wrapped ? 1 : 0);
  p.i64(static_cast<std::int64_t>(settings.mimic_joints.size()));
  for (const MimicJoint& m : settings.mimic_joints) {
    p.i64(m.dof_a);
    p.i64(m.dof_b);
    for (double v : {m.gear_ratio, m.offset, m.natural_frequency, m.damping_ratio}) p.f64(v);
  }
}

void read_joint_coupling(ByteReader& r, const Model& model, Settings& settings,
                         const std::string& name) {
  for (int d = 0; d < model.nv; ++d) {
    const std::uint8_t wrapped = r.u8();
    if (wrapped > 1)
      fail_checkpoint(name, "corrupt checkpoint: revolute wrap " + std::to_string(wrapped) +
                                " of dof " + std::to_string(d) + " is neither 0 nor 1");
    if (wrapped || model.links[model.dof_link[d]].joint_type == JointType::revolute)
      settings.revolute_wrap[static_cast<size_t>(d)] =
          wrapped ? RevoluteWrap::wrapped : RevoluteWrap::unwrapped;
  }
  const std::int64_t count = r.i64();
  if (count < 0 || count > model.nv)
    fail_checkpoint(name, "corrupt checkpoint: " + count_of(count, "mimic joint") + " for " +
                              count_of(model.nv, "dof"));
  std::vector<MimicJoint> rows(static_cast<size_t>(count));
  for (MimicJoint& m : rows) {
    const std::int64_t a = r.i64(), b = r.i64();
    if (a < 0 || a >= model.nv || b < 0 || b >= model.nv)
      fail_checkpoint(name, "corrupt checkpoint: a mimic joint couples dofs " + std::to_string(a) +
                                " and " + std::to_string(b) + " of " + std::to_string(model.nv));
    m = {static_cast<int>(a), static_cast<int>(b), r.f64(), r.f64(), r.f64(), r.f64()};
  }
  settings.mimic_joints = std::move(rows);
}

}  // namespace

std::uint64_t model_fingerprint(const Model& model) {
  Writer w;
  w.u32(static_cast<std::uint32_t>(model.nq));
  w.u32(static_cast<std::uint32_t>(model.nv));
  w.u32(static_cast<std::uint32_t>(model.links.size()));
  for (int i = 0; i < 3; ++i) hash_double(w, model.gravity[i]);
  for (const Link& link : model.links) {
    w.text(link.name);
    w.i64(link.parent);
    w.text(link.joint_name);
    w.u8(static_cast<std::uint8_t>(link.joint_type));
    hash_double(w, link.mass);
    for (int i = 0; i < 3; ++i) hash_double(w, link.com[i]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) hash_double(w, link.inertia_com(r, c));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) hash_double(w, link.tree_transform.E(r, c));
    for (int i = 0; i < 3; ++i) hash_double(w, link.tree_transform.r[i]);
    for (int i = 0; i < 3; ++i) hash_double(w, link.axis[i]);
    w.i64(link.q_index);
    w.i64(link.v_index);
  }
  for (const VecX* v : {&model.armature, &model.lower_limit, &model.upper_limit}) w.vec(*v);
  // The collision shapes, where there are any (a model without keeps its older fingerprint).
  if (!model.shapes.empty()) w.i64(static_cast<std::int64_t>(model.shapes.size()));
  for (const CollisionShape& s : model.shapes) {
    w.i64(s.link);
    w.i64(static_cast<std::int64_t>(s.type));
    for (int i = 0; i < 3; ++i) hash_double(w, s.size[i]);
    for (int i = 0; i < 3; ++i) hash_double(w, s.position[i]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) hash_double(w, s.rotation(r, c));
    for (double v : {s.material.static_friction, s.material.dynamic_friction,
                     s.material.restitution})
      hash_double(w, v);
    for (const Vec3& v : s.vertices)  // convex hulls only: other shapes keep their fingerprint
      for (int i = 0; i < 3; ++i) hash_double(w, v[i]);
  }
  return fnv1a(w.str().data(), w.str().size());
}

std::string checkpoint_bytes(const Simulation& sim) {
  const Model& model = sim.model();
  const Settings& settings = sim.settings();
  const State state = sim.state();
  Writer p;  // payload
  p.f64(state.time);
  p.i64(state.step_count);
  const SimulationOptions& o = settings.options;
  p.f64(o.dt);
  p.u8(static_cast<std::uint8_t>(o.solver));
  p.i64(o.position_iterations);
  p.i64(o.velocity_iterations);
  p.u8(static_cast<std::uint8_t>(o.compat));
  p.vec(state.q);
  p.vec(state.qd);
  p.vec(state.applied_force);
  for (int d = 0; d < model.nv; ++d) {
    const auto k = static_cast<size_t>(d);
    const Drive& drive = settings.drives[k];
    p.u8(static_cast<std::uint8_t>(drive.type));
    for (double v : {drive.stiffness, drive.damping, drive.max_force, drive.max_impulse,
                     drive.target_position, drive.target_velocity})
      p.f64(v);
    p.f64(settings.lower_limit[d]);
    p.f64(settings.upper_limit[d]);
    p.f64(settings.max_joint_velocity[d]);
    const JointFriction& f = settings.friction[k];
    for (double v : {f.static_effort, f.dynamic_effort, f.viscous}) p.f64(v);
    const ActuatorEnvelope& e = settings.envelopes[k];
    for (double v : {e.max_effort, e.max_actuator_velocity, e.speed_effort_gradient,
                     e.velocity_dependent_resistance})
      p.f64(v);
    p.f64(settings.friction_coefficient[d]);
  }
  for (const LinkParameters& l : settings.link_parameters)
    for (double v : {l.cfm_scale, l.linear_damping, l.angular_damping, l.max_linear_velocity,
                     l.max_angular_velocity})
      p.f64(v);
  p.vec(state.drive_force);
  p.vec(state.limit_force);
  p.vec(state.friction_force);
  p.vec(state.velocity_limit_force);
  write_actuators(p, settings, state);
  write_drive_delays(p, settings, state);
  write_joint_coupling(p, settings);
  const GuardAccount& account = state.guard_account;  // version 7
  for (double v : {account.created, account.dissipated, account.scale}) p.f64(v);
  write_contact_settings(p, settings);  // version 8
  write_friction_anchors(p, state);
  p.u8(settings.contact.self_collision ? 1 : 0);  // version 9
  write_row_kinds(p, settings, state);            // version 10

  Writer w;
  w.bytes(kMagic, sizeof(kMagic));
  w.u32(kCheckpointVersion);
  w.u64(model_fingerprint(model));
  w.u32(static_cast<std::uint32_t>(model.nq));
  w.u32(static_cast<std::uint32_t>(model.nv));
  w.u64(p.str().size());
  w.bytes(p.str().data(), p.str().size());
  w.u64(fnv1a(w.str().data(), w.str().size()));
  return std::move(w.str());
}

void restore_checkpoint(const std::string& bytes, Simulation& sim, const std::string& name) {
  if (std::memcmp(bytes.data(), kMagic, std::min(bytes.size(), sizeof(kMagic))) != 0)
    fail_checkpoint(
        name, "not a featherdrive checkpoint (the file does not start with the checkpoint magic)");
  if (bytes.size() < kHeaderSize + 8)
    fail_checkpoint(name, "truncated checkpoint: " + std::to_string(bytes.size()) +
                              " bytes, shorter than the header");
  ByteReader h(bytes, sizeof(kMagic), kHeaderSize, name);
  const std::uint32_t version = h.u32();
  if (version < kOldestCheckpointVersion || version > kCheckpointVersion)
    fail_checkpoint(name, "checkpoint format version " + std::to_string(version) +
                              " is not supported (this build reads versions " +
                              std::to_string(kOldestCheckpointVersion) + " to " +
                              std::to_string(kCheckpointVersion) + ")");
  const std::uint64_t fingerprint = h.u64();
  const std::uint32_t nq = h.u32();
  const std::uint32_t nv = h.u32();
  const std::uint64_t payload = h.u64();
  if (payload > bytes.size())
    fail_checkpoint(name, "truncated checkpoint: the header announces a payload of " +
                              std::to_string(payload) + " bytes, the file has " +
                              std::to_string(bytes.size()));
  const std::uint64_t expected = kHeaderSize + payload + 8;
  if (bytes.size() != expected)
    fail_checkpoint(name, std::string(bytes.size() < expected ? "truncated" : "corrupt") +
                              " checkpoint: the header announces " + std::to_string(expected) +
                              " bytes, the file has " + std::to_string(bytes.size()));
  ByteReader tail(bytes, bytes.size() - 8, bytes.size(), name);
  const std::uint64_t stored = tail.u64();
  const std::uint64_t computed = fnv1a(bytes.data(), bytes.size() - 8);
  if (stored != computed)
    fail_checkpoint(name, "corrupt checkpoint: checksum " + hex(computed) +
                              " does not match the stored " + hex(stored));

  const Model& model = sim.model();
  const std::uint64_t ours = model_fingerprint(model);
  if (fingerprint != ours || nq != static_cast<std::uint32_t>(model.nq) ||
      nv != static_cast<std::uint32_t>(model.nv))
    fail_checkpoint(name, "the checkpoint is of a different model (nq " + std::to_string(nq) +
                              ", nv " + std::to_string(nv) + ", fingerprint " + hex(fingerprint) +
                              "; this model: nq " + std::to_string(model.nq) + ", nv " +
                              std::to_string(model.nv) + ", fingerprint " + hex(ours) + ")");

  // The checkpoint's settings and state as values; the simulation's where the version has none
  // (drive delays before 4, wrap and mimic joints before 5). Actuators and delays are the
  // checkpoint's, or none.
  const Settings& held = sim.settings();
  Settings settings = held;
  std::fill(settings.actuators.begin(), settings.actuators.end(), ExplicitActuator{});
  settings.actuator_feedforward.setZero();
  std::fill(settings.drive_delay.begin(), settings.drive_delay.end(), 0);
  State state;
  state.actuator_history.resize(static_cast<size_t>(model.nv));
  state.drive_delay_history.resize(static_cast<size_t>(model.nv));
  ByteReader r(bytes, kHeaderSize, bytes.size() - 8, name);
  // Restored into a copy, so that sim stays as it was if any value is refused.
  Simulation next = sim;
  try {
    state.time = r.f64();
    const std::int64_t step_count = r.i64();
    // The clock must be one a run reaches (check_clock's rule), or resuming overflows.
    if (step_count < 0 || step_count > kMaxStepCount)
      fail_checkpoint(name, "corrupt checkpoint: step count " + std::to_string(step_count) +
                                " is outside [0, " + std::to_string(kMaxStepCount) + "]");
    const double time = state.time;
    if (!std::isfinite(time) || time < 0.0 || time > 2.0 * static_cast<double>(step_count) * kMaxDt)
      fail_checkpoint(name, "corrupt checkpoint: time " + format_double(time) + " s after " +
                                std::to_string(step_count) +
                                " steps is not one a run reaches (finite, >= 0, "
                                "at most 2 * steps * " +
                                format_double(kMaxDt) + " s)");
    state.step_count = static_cast<long>(step_count);
    SimulationOptions& o = settings.options;
    o = SimulationOptions{};
    o.guard = held.options.guard;  // how to step, not state: the simulation's own
    o.dt = r.f64();
    const std::uint8_t solver = r.u8();
    if (solver > static_cast<std::uint8_t>(SolverType::tgs))
      fail_checkpoint(name, "corrupt checkpoint: solver = " + std::to_string(solver));
    o.solver = static_cast<SolverType>(solver);
    const std::int64_t pos = r.i64(), vel = r.i64();
    if (pos < 1 || pos > kMaxIterations)
      fail_checkpoint(name, "corrupt checkpoint: position_iterations " + std::to_string(pos) +
                                " is outside [1, " + std::to_string(kMaxIterations) + "]");
    if (vel < 0 || vel > kMaxIterations)
      fail_checkpoint(name, "corrupt checkpoint: velocity_iterations " + std::to_string(vel) +
                                " is outside [0, " + std::to_string(kMaxIterations) + "]");
    o.position_iterations = static_cast<int>(pos);
    o.velocity_iterations = static_cast<int>(vel);
    const std::uint8_t compat = r.u8();
    if (compat > static_cast<std::uint8_t>(Compat::physx))
      fail_checkpoint(name, "corrupt checkpoint: compat = " + std::to_string(compat));
    o.compat = static_cast<Compat>(compat);
    if (o.compat != held.options.compat)
      fail_checkpoint(name, std::string("the checkpoint is of a compat ") + to_string(o.compat) +
                                " simulation, this simulation is compat " +
                                to_string(held.options.compat) +
                                " (compat is chosen when a simulation is made)");
    state.q = r.vec(model.nq);
    state.qd = r.vec(model.nv);
    state.applied_force = r.vec(model.nv);
    for (int d = 0; d < model.nv; ++d) {
      const auto k = static_cast<size_t>(d);
      Drive& drive = settings.drives[k];
      const std::uint8_t type = r.u8();
      if (type > static_cast<std::uint8_t>(DriveType::acceleration))
        fail_checkpoint(name, "corrupt checkpoint: drive type " + std::to_string(type) +
                                  " of dof " + std::to_string(d));
      drive.type = static_cast<DriveType>(type);
      drive.stiffness = r.f64();
      drive.damping = r.f64();
      drive.max_force = r.f64();
      drive.max_impulse = r.f64();
      drive.target_position = r.f64();
      drive.target_velocity = r.f64();
      const double lower = r.f64(), upper = r.f64(), max_velocity = r.f64();
      JointFriction f;
      f.static_effort = r.f64();
      f.dynamic_effort = r.f64();
      f.viscous = r.f64();
      ActuatorEnvelope e;
      e.max_effort = r.f64();
      e.max_actuator_velocity = r.f64();
      e.speed_effort_gradient = r.f64();
      e.velocity_dependent_resistance = r.f64();
      const double friction_coefficient = r.f64();
      // The per-joint settings exist for revolute, prismatic and spherical joints only; elsewhere
      // the simulation's values stand (no setter can change them, so a run saved them as they
      // are), and Settings::validate passes a value equal to the default as it is.
      const JointType jt = model.links[model.dof_link[d]].joint_type;
      if (jt != JointType::revolute && jt != JointType::prismatic &&
          jt != JointType::spherical) {
        const JointFriction& f0 = held.friction[k];
        const ActuatorEnvelope& e0 = held.envelopes[k];
        const double saved[] = {lower,
                                upper,
                                max_velocity,
                                f.static_effort,
                                f.dynamic_effort,
                                f.viscous,
                                e.max_effort,
                                e.max_actuator_velocity,
                                e.speed_effort_gradient,
                                e.velocity_dependent_resistance,
                                friction_coefficient};
        const double kept[] = {held.lower_limit[d],
                               held.upper_limit[d],
                               held.max_joint_velocity[d],
                               f0.static_effort,
                               f0.dynamic_effort,
                               f0.viscous,
                               e0.max_effort,
                               e0.max_actuator_velocity,
                               e0.speed_effort_gradient,
                               e0.velocity_dependent_resistance,
                               held.friction_coefficient[d]};
        for (int i = 0; i < 11; ++i)
          if (std::bit_cast<std::uint64_t>(saved[i]) != std::bit_cast<std::uint64_t>(kept[i]))
            fail_checkpoint(
                name, "corrupt checkpoint: dof " + std::to_string(d) + " of " + to_string(jt) +
                          " joint '" + model.links[model.dof_link[d]].joint_name +
                          "' has joint setting #" + std::to_string(i) + " = " +
                          format_double(saved[i]) +
                          ", which only a revolute, prismatic or spherical joint can change");
        continue;
      }
      settings.lower_limit[d] = lower;
      settings.upper_limit[d] = upper;
      settings.max_joint_velocity[d] = max_velocity;
      settings.friction[k] = f;
      settings.envelopes[k] = e;
      settings.friction_coefficient[d] = friction_coefficient;
    }
    for (LinkParameters& l : settings.link_parameters) {
      l.cfm_scale = r.f64();
      l.linear_damping = r.f64();
      l.angular_damping = r.f64();
      l.max_linear_velocity = r.f64();
      l.max_angular_velocity = r.f64();
    }
    state.drive_force = r.vec(model.nv);
    state.limit_force = r.vec(model.nv);
    state.friction_force = r.vec(model.nv);
    state.velocity_limit_force = r.vec(model.nv);
    read_actuators(r, settings, state, name, version);
    if (version >= 4) read_drive_delays(r, settings, state, name);    // version 3 has none
    if (version >= 5) read_joint_coupling(r, model, settings, name);  // 3 and 4 have none
    GuardAccount& account = state.guard_account;  // before version 7, it starts empty
    if (version >= 7) {
      account.created = r.f64();
      account.dissipated = r.f64();
      account.scale = r.f64();
    }
    if (version >= 8) {  // before, the simulation's own settings and no kept anchors
      read_contact_settings(r, settings);
      read_friction_anchors(r, model, state);
    }
    if (version >= 9) settings.contact.self_collision = r.u8() != 0;  // before, off
    // Before version 10, the simulation's own row kind settings and no row kind forces.
    state.row_force = VecX::Zero(RowKinds::size * model.nv);
    if (version >= 10) read_row_kinds(r, model, settings, state, name);
    if (r.pos() != bytes.size() - 8)
      fail_checkpoint(name, "corrupt checkpoint: " + std::to_string(bytes.size() - 8 - r.pos()) +
                                " bytes left over after the payload");
    next.set_settings(settings);
    next.set_state(state);
  } catch (const CheckpointError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    fail_checkpoint(name, std::string("bad value in the checkpoint: ") + e.what());
  }
  // Copied, not moved: same sizes, so every buffer stays where it is and views of sim stay valid.
  sim = next;
}

void save_checkpoint(const Simulation& sim, const std::filesystem::path& path) {
  const std::string bytes = checkpoint_bytes(sim);
  AtomicFile out(path, "the checkpoint");
  out.stream() << bytes;
  out.commit();
}

void load_checkpoint(const std::filesystem::path& path, Simulation& sim) {
  std::string bytes;
  try {
    bytes = read_input_file(path, "the checkpoint");
  } catch (const InputError& e) {
    throw CheckpointError(e.what());
  }
  restore_checkpoint(bytes, sim, path.string());
}

}  // namespace featherdrive
