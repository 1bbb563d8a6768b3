// The Python module `featherdrive`: thin pybind11 bindings over the C++ API with the same names.
// Vectors come back as read-only numpy views onto the Simulation's Eigen vectors (no copy; the
// view keeps the Simulation alive); arrays going in are checked for shape and dtype here so that
// a wrong one raises ValueError naming it. C++ std::invalid_argument (ModelError, InputError) ->
// ValueError, DivergenceError (std::runtime_error) -> RuntimeError, with the C++ message.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <chrono>
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
using namespace featherdrive;

void bind_fit(py::module_& m);  // python/bind_fit.cpp

namespace {

using ModelPtr = std::shared_ptr<Model>;
constexpr long long kIntMax = std::numeric_limits<int>::max();

// ---- integers -------------------------------------------------------------------------------
// Every integer from Python is read in 64 bits and range-checked before it is narrowed: ValueError
// naming the argument and the value. int, numpy integers and anything with __index__ are integers;
// bool is refused (True as a count or an index is a mistake) and so are floats: TypeError.

std::string type_name(py::handle obj) {
  return py::str(py::type::handle_of(obj).attr("__name__")).cast<std::string>();
}

bool is_integer(py::handle obj) {
  if (PyBool_Check(obj.ptr())) return false;
  if (PyLong_Check(obj.ptr())) return true;
  if (!PyIndex_Check(obj.ptr())) return false;
  return !py::isinstance(obj, py::module_::import("numpy").attr("bool_"));
}

/// obj as a 64-bit integer in [lo, hi].
long long to_int64(py::handle obj, const std::string& what, long long lo, long long hi) {
  if (!is_integer(obj))
    throw py::type_error(what + " must be an integer, not " + type_name(obj) + " (" +
                         py::repr(obj).cast<std::string>() + ")");
  const auto index = py::reinterpret_steal<py::object>(PyNumber_Index(obj.ptr()));
  if (!index) throw py::error_already_set();
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
  if (v == -1 && PyErr_Occurred()) throw py::error_already_set();
  if (overflow != 0 || v < lo || v > hi)
    throw py::value_error(what + " = " + py::str(index).cast<std::string>() +
                          " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) +
                          "]");
  return v;
}

int to_int(py::handle obj, const std::string& what, long long lo, long long hi = kIntMax) {
  return static_cast<int>(to_int64(obj, what, lo, std::min(hi, kIntMax)));
}

/// A str argument as UTF-8; TypeError naming `what` for anything else.
std::string to_str(py::handle obj, const std::string& what) {
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

NameOrIndex to_name_or_index(py::handle obj, const std::string& what, const char* expected) {
  if (py::isinstance<py::str>(obj)) return {to_str(obj, what), -1, true};
  if (!is_integer(obj))
    throw py::type_error(what + " = " + py::repr(obj).cast<std::string>() + ": expected " +
                         expected + ", not " + type_name(obj));
  return {"", to_int64(obj, what, std::numeric_limits<long long>::min(),
                       std::numeric_limits<long long>::max()), false};
}

// ---- per-object locks -----------------------------------------------------------------------
// Python threads may share a Simulation or Batch: every binding that reads or writes one holds
// its lock, so calls on one object are serialised (whole calls: a step(n) runs its n steps before
// another call on that object starts). The lock is waited for with the GIL released, so that its
// holder can re-take the GIL (step() runs without it); the main thread's wait answers Ctrl-C. The
// table maps an object's address to its lock and is only touched with the GIL held, which guards
// it. A copy inside a Batch maps to the batch's lock (Batch.sim registers it). The entries of an
// object go when the Python object owning it is freed (the holders' deleters).

struct ObjectLock {
  std::timed_mutex mutex;
};

using LockTable = std::unordered_map<const void*, std::shared_ptr<ObjectLock>>;

LockTable& lock_table() {
  static auto* table = new LockTable;  // never destroyed: deleters may run during interpreter exit
  return *table;
}

std::shared_ptr<ObjectLock> lock_for(const void* object) {
  std::shared_ptr<ObjectLock>& lock = lock_table()[object];
  if (!lock) lock = std::make_shared<ObjectLock>();
  return lock;
}

unsigned long main_thread_id = 0;  // set at import

bool on_main_thread() { return PyThread_get_thread_ident() == main_thread_id; }

/// Raises KeyboardInterrupt (or what a signal handler raised) if a signal came; call without the
/// GIL, on the main thread (the only one Python runs signal handlers on).
void check_signals() {
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
}

/// Holds an object's lock for its scope.
class Hold {
 public:
  /// With the GIL held: waits without it if another thread holds the lock.
  explicit Hold(const void* object) : lock_(lock_for(object)) {
    if (lock_->mutex.try_lock()) return;
    py::gil_scoped_release nogil;
    wait();
  }
  /// Without the GIL (lock from lock_for, taken with the GIL).
  explicit Hold(std::shared_ptr<ObjectLock> lock) : lock_(std::move(lock)) { wait(); }
  ~Hold() { lock_->mutex.unlock(); }
  Hold(const Hold&) = delete;
  Hold& operator=(const Hold&) = delete;

 private:
  void wait() {
    if (!on_main_thread()) return lock_->mutex.lock();
    while (!lock_->mutex.try_lock_for(std::chrono::milliseconds(20))) check_signals();
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
    if (took < std::chrono::milliseconds(2) && chunk <= kIntMax / 2) chunk *= 2;
    else if (took > std::chrono::milliseconds(20) && chunk > 1) chunk /= 2;
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
ModelPtr to_python(const std::shared_ptr<const Model>& model) {
  return std::const_pointer_cast<Model>(model);
}

std::string shape_of(const py::array& a) {
  std::ostringstream s;
  s << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i) << (a.ndim() == 1 ? "," : "");
  s << ")";
  return s.str();
}

/// obj as a C-contiguous float64 array; ValueError naming `what` unless its dtype is real numbers.
py::array_t<double, py::array::c_style> as_float_array(py::handle obj, const std::string& what) {
  py::array a = py::module_::import("numpy").attr("asarray")(obj);
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw std::invalid_argument(what + " has dtype " + py::str(a.dtype()).cast<std::string>() +
                                ": expected real numbers (float64)");
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
}

/// A vector of n values: an array of shape (n,), or a scalar for all n.
VecX to_vector(py::handle obj, Eigen::Index n, const std::string& what, bool scalar_ok = false) {
  const auto a = as_float_array(obj, what);
  if (scalar_ok && a.ndim() == 0) return VecX::Constant(n, *a.data());
  if (a.ndim() != 1 || a.shape(0) != n)
    throw std::invalid_argument(what + " has shape " + shape_of(a) + ", expected (" +
                                std::to_string(n) + ",)");
  VecX v(n);
  if (n > 0) std::memcpy(v.data(), a.data(), sizeof(double) * static_cast<size_t>(n));
  return v;
}

Vec3 to_vec3(py::handle obj, const std::string& what) { return to_vector(obj, 3, what); }

Mat3 to_mat3(py::handle obj, const std::string& what) {
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
RowMatrix to_rows(py::handle obj, size_t k, Eigen::Index cols, const std::string& what,
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
py::array read_only(RowMatrix m) {
  py::array a = py::cast(std::move(m));
  a.attr("flags").attr("writeable") = false;
  return a;
}

/// env_ids of a batch of n: None for all, an integer, or a sequence or array of integers (range
/// and repeats are checked by Batch).
std::vector<int> to_env_ids(py::handle obj, int n) {
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
std::vector<Observation> to_observations(py::handle fields) {
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
      throw std::invalid_argument("observe: field '" + name + "' is not one of q, qd, "
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

SolverType to_solver(py::handle obj) {
  return to_enum<SolverType>(obj, "solver", {{"pgs", SolverType::pgs}, {"tgs", SolverType::tgs}},
                             "'pgs' or 'tgs'");
}

DriveType to_drive_type(py::handle obj) {
  return to_enum<DriveType>(obj, "drive type",
                            {{"none", DriveType::none},
                             {"force", DriveType::force},
                             {"acceleration", DriveType::acceleration}},
                            "'none', 'force' or 'acceleration'");
}

UrdfEffort to_urdf_effort(py::handle obj) {
  return to_enum<UrdfEffort>(obj, "effort",
                             {{"none", UrdfEffort::none},
                              {"max_force", UrdfEffort::max_force},
                              {"effort_limit", UrdfEffort::effort_limit}},
                             "'none', 'max_force' or 'effort_limit'");
}

Compat to_compat(py::handle obj) {
  return to_enum<Compat>(obj, "compat", {{"none", Compat::none}, {"physx", Compat::physx}},
                         "'none' or 'physx'");
}

// Explicit actuators: the kind by name, the remotized table as an (n, 2) array or None.
ActuatorKind to_actuator_kind(py::handle obj) {
  return to_enum<ActuatorKind>(obj, "actuator kind",
                               {{"none", ActuatorKind::none},
                                {"ideal_pd", ActuatorKind::ideal_pd},
                                {"dc_motor", ActuatorKind::dc_motor},
                                {"remotized_pd", ActuatorKind::remotized_pd}},
                               "'none', 'ideal_pd', 'dc_motor' or 'remotized_pd'");
}

std::vector<std::pair<double, double>> to_lookup(py::handle obj) {
  std::vector<std::pair<double, double>> table;
  if (obj.is_none()) return table;
  const auto a = as_float_array(obj, "lookup");
  if (a.ndim() != 2 || a.shape(1) != 2)
    throw std::invalid_argument("lookup has shape " + shape_of(a) +
                                ", expected (n, 2): rows of (position, max effort)");
  for (py::ssize_t i = 0; i < a.shape(0); ++i) table.emplace_back(a.at(i, 0), a.at(i, 1));
  return table;
}

ExplicitActuator make_actuator(ActuatorKind kind, double stiffness, double damping,
                               double effort_limit, double saturation_effort,
                               double velocity_limit, py::handle lookup, py::handle delay) {
  ExplicitActuator a;
  a.kind = kind;
  a.stiffness = stiffness;
  a.damping = damping;
  a.effort_limit = effort_limit;
  a.saturation_effort = saturation_effort;
  a.velocity_limit = velocity_limit;
  a.lookup = to_lookup(lookup);
  a.delay = to_int(delay, "delay", 0, kMaxActuatorDelay);
  return a;
}

SimulationOptions make_options(double dt, py::handle solver, py::handle position_iterations,
                               py::handle velocity_iterations, py::handle compat = py::none()) {
  SimulationOptions o;
  o.dt = dt;
  if (!compat.is_none()) o.compat = to_compat(compat);
  o.solver = to_solver(solver);
  o.position_iterations = to_int(position_iterations, "position_iterations", 1);
  o.velocity_iterations = to_int(velocity_iterations, "velocity_iterations", 0);
  validate_options(o);
  return o;
}

NameOrIndex joint_arg(py::handle joint) {
  return to_name_or_index(joint, "joint", "a joint name (str) or a dof index (int)");
}

NameOrIndex link_arg(py::handle link) {
  return to_name_or_index(link, "link", "a link name (str) or a link index (int)");
}

int index_in(long long index, int size, const char* what) {
  if (index < 0 || index >= size)
    throw std::invalid_argument(std::string(what) + " " + std::to_string(index) +
                                " is out of range [0, " + std::to_string(size) + ")");
  return static_cast<int>(index);
}

/// The dof of a joint given by name (its first dof) or by dof index.
int dof_of(const Model& model, const NameOrIndex& joint) {
  return joint.named ? model.dof_index(joint.name) : index_in(joint.index, model.nv, "dof index");
}

int link_of(const Model& model, const NameOrIndex& link) {
  return link.named ? model.link_index(link.name)
                    : index_in(link.index, model.num_links(), "link index");
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

std::string fmt(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr auto ref = py::return_value_policy::reference_internal;

// Docstrings shared by Simulation and Batch.
constexpr const char* kSolverDoc = "'pgs' or 'tgs' (or a SolverType)";

// ---- kinematics and dynamics ------------------------------------------------------------------
// Queries at a state: a Simulation's current q and qd (copied under its lock, then computed on a
// private workspace) or a model at a given q (and qd), checked as Simulation.set_q and set_qd
// check them. Every result is a new numpy array (a copy). Conventions: docs/conventions.md,
// "Kinematics and dynamics".

struct KinematicState {
  std::shared_ptr<const Model> model;
  VecX q, qd;
};

KinematicState state_of(const Simulation& s) {
  return locked(s, [&] { return KinematicState{s.model_ptr(), s.q(), s.qd()}; });
}

/// q (and qd unless None; zero then) checked and normalised by a scratch simulation's setters.
KinematicState state_at(const ModelPtr& model, py::handle q, py::handle qd) {
  if (!model) throw py::type_error("model must be a Model, not None");
  Simulation check(model, SimulationOptions{});
  check.set_q(to_vector(q, model->nq, "q"));
  if (!qd.is_none()) check.set_qd(to_vector(qd, model->nv, "qd"));
  return {model, check.q(), check.qd()};
}

ReferenceFrame to_reference(py::handle obj) {
  return to_enum<ReferenceFrame>(
      obj, "frame",
      {{"local", ReferenceFrame::local}, {"world_aligned", ReferenceFrame::world_aligned}},
      "'local' or 'world_aligned'");
}

Vec3 to_point(py::handle obj) { return obj.is_none() ? Vec3::Zero() : to_vec3(obj, "point"); }

/// A link's query: the state's kinematics (with velocities) and the link's index.
struct LinkQuery {
  KinematicState state;
  Data data;
  int link;
  LinkQuery(KinematicState s, py::handle link_obj)
      : state(std::move(s)), data(*state.model), link(link_of(*state.model, link_arg(link_obj))) {
    forward_kinematics(*state.model, data, state.q, state.qd);
  }
  const Model& model() const { return *state.model; }
};

py::tuple link_pose_of(const LinkQuery& k) {
  return py::make_tuple(Mat3(k.data.world_rotation[k.link]), Vec3(k.data.world_position[k.link]));
}

Vec6 frame_velocity_of(const LinkQuery& k, py::handle point, py::handle frame) {
  return frame_velocity(k.model(), k.data, k.link, to_point(point), to_reference(frame));
}

MatX jacobian_of(const LinkQuery& k, py::handle point, py::handle frame) {
  MatX J;
  frame_jacobian(k.model(), k.data, k.link, to_point(point), to_reference(frame), J);
  return J;
}

Vec6 jacobian_dot_of(const LinkQuery& k, py::handle point, py::handle frame) {
  return jacobian_dot_times_v(k.model(), k.data, k.link, to_point(point), to_reference(frame));
}

/// The whole robot's queries (no link).
struct RobotQuery {
  KinematicState state;
  Data data;
  explicit RobotQuery(KinematicState s) : state(std::move(s)), data(*state.model) {
    forward_kinematics(*state.model, data, state.q, state.qd);
  }
  const Model& model() const { return *state.model; }
  MatX mass_matrix() { return crba(model(), data, state.q); }
  VecX bias_forces() { return nonlinear_effects(model(), data, state.q, state.qd); }
  VecX gravity_forces() { return generalized_gravity(model(), data, state.q); }
  VecX inverse_dynamics(py::handle qdd) {
    return rnea(model(), data, state.q, state.qd, to_vector(qdd, model().nv, "qdd"));
  }
  Vec3 com() { return center_of_mass(model(), data); }
  Vec3 com_velocity() { return center_of_mass_velocity(model(), data); }
  MatX com_jacobian() {
    MatX J;
    center_of_mass_jacobian(model(), data, J);
    return J;
  }
};

/// A whole-robot query as a Simulation method and as a module function of (model, q) or, with
/// with_qd, (model, q, qd).
template <class R>
void def_robot_query(py::class_<Simulation, SimulationHolder>& sim, py::module_& m,
                     const char* name, R (RobotQuery::*query)(), bool with_qd,
                     const std::string& doc) {
  sim.def(name, [query](const Simulation& s) { return (RobotQuery(state_of(s)).*query)(); },
          (doc + " At the simulation's current q and qd; a new array (a copy).").c_str());
  if (with_qd)
    m.def(name, [query](const ModelPtr& mo, py::handle q, py::handle qd) {
      return (RobotQuery(state_at(mo, q, qd)).*query)();
    }, py::arg("model"), py::arg("q"), py::arg("qd"), (doc + " At q (nq,) and qd (nv,), checked "
       "as Simulation.set_q and set_qd check them; a new array.").c_str());
  else
    m.def(name, [query](const ModelPtr& mo, py::handle q) {
      return (RobotQuery(state_at(mo, q, py::none())).*query)();
    }, py::arg("model"), py::arg("q"),
          (doc + " At q (nq,), checked as Simulation.set_q checks it; a new array.").c_str());
}

constexpr const char* kFrameDoc =
    " frame: 'world_aligned' (world axes, origin at the point; the default) or 'local' (the "
    "link's axes). Spatial vectors are [angular; linear].";

void bind_dynamics(py::module_& m) {
  py::enum_<ReferenceFrame>(m, "ReferenceFrame",
                            "Axes of a spatial velocity or Jacobian: local (the link's) or "
                            "world_aligned (the world's), origin at the point either way.")
      .value("local", ReferenceFrame::local)
      .value("world_aligned", ReferenceFrame::world_aligned);

  auto sim = py::reinterpret_borrow<py::class_<Simulation, SimulationHolder>>(m.attr("Simulation"));
  const auto link = py::arg("link");
  const auto point = py::arg("point") = py::none();
  const auto frame = py::arg("frame") = "world_aligned";
  const auto model = py::arg("model"), q = py::arg("q"), qd = py::arg("qd");
  const std::string at_sim = " At the simulation's current q and qd; a new array (a copy).";
  const std::string at_q = " At q (nq,), checked as Simulation.set_q checks it; a new array.";
  const std::string at_qd =
      " At q (nq,) and qd (nv,), checked as Simulation.set_q and set_qd check them; a new array.";
  const std::string pose_doc =
      "(R, p) of a link (name or index): its axes R (3, 3) and origin p (3,) in the world.";
  const std::string point_doc =
      "World position (3,) of a point (3,) fixed on a link (name or index), given in the link "
      "frame.";
  const std::string velocity_doc =
      std::string("Spatial velocity (6,) [omega; velocity of the point] of a point on a link "
                  "(point in the link frame; None: the link origin).") + kFrameDoc;
  const std::string jacobian_doc =
      std::string("J (6, nv) with J qd = frame_velocity(link, point, frame); columns for qd "
                  "(a floating root's body-frame twist).") + kFrameDoc;
  const std::string jdot_doc =
      std::string("dJ/dt qd (6,) for jacobian(link, point, frame): the acceleration at qdd = 0, "
                  "gravity excluded; classical (d/dt [omega; point velocity]) when "
                  "world_aligned, spatial in the link's axes when local.") + kFrameDoc;
  const std::string mass_doc = "Joint-space inertia M(q) (nv, nv), armature included (CRBA).";
  const std::string bias_doc =
      "Bias forces b = C(q, qd) qd + g(q) (nv,): M qdd + b = tau (MuJoCo's qfrc_bias).";
  const std::string gravity_doc =
      "g(q) (nv,): the joint forces that hold q still against gravity.";
  const std::string id_doc =
      "Inverse dynamics tau = M qdd + b (nv,) for joint accelerations qdd (nv,) (RNEA).";
  const std::string com_doc = "Centre of mass (3,) of the whole robot, world coordinates.";
  const std::string comv_doc = "Velocity (3,) of the centre of mass, world coordinates.";
  const std::string comj_doc = "J_com (3, nv): J_com qd is the centre of mass's velocity.";

  // On a Simulation.
  sim.def("link_pose", [](const Simulation& s, py::handle l) {
        return link_pose_of(LinkQuery(state_of(s), l));
      }, link, (pose_doc + at_sim).c_str())
      .def("frame_position", [](const Simulation& s, py::handle l, py::handle p) {
        const Vec3 pt = to_vec3(p, "point");
        LinkQuery k(state_of(s), l);
        return frame_position(k.model(), k.data, k.link, pt);
      }, link, py::arg("point"), (point_doc + at_sim).c_str())
      .def("frame_velocity", [](const Simulation& s, py::handle l, py::handle p, py::handle f) {
        return frame_velocity_of(LinkQuery(state_of(s), l), p, f);
      }, link, point, frame, (velocity_doc + at_sim).c_str())
      .def("jacobian", [](const Simulation& s, py::handle l, py::handle p, py::handle f) {
        return jacobian_of(LinkQuery(state_of(s), l), p, f);
      }, link, point, frame, (jacobian_doc + at_sim).c_str())
      .def("jacobian_dot_times_qd",
           [](const Simulation& s, py::handle l, py::handle p, py::handle f) {
             return jacobian_dot_of(LinkQuery(state_of(s), l), p, f);
           }, link, point, frame, (jdot_doc + at_sim).c_str())
      .def("inverse_dynamics", [](const Simulation& s, py::handle qdd) {
        return RobotQuery(state_of(s)).inverse_dynamics(qdd);
      }, py::arg("qdd"), (id_doc + at_sim).c_str());
  def_robot_query(sim, m, "mass_matrix", &RobotQuery::mass_matrix, false, mass_doc);
  def_robot_query(sim, m, "bias_forces", &RobotQuery::bias_forces, true, bias_doc);
  def_robot_query(sim, m, "gravity_forces", &RobotQuery::gravity_forces, false, gravity_doc);
  def_robot_query(sim, m, "center_of_mass", &RobotQuery::com, false, com_doc);
  def_robot_query(sim, m, "center_of_mass_velocity", &RobotQuery::com_velocity, true, comv_doc);
  def_robot_query(sim, m, "center_of_mass_jacobian", &RobotQuery::com_jacobian, false,
                  comj_doc);

  // The same as module functions of (model, q[, qd]).
  m.def("link_pose", [](const ModelPtr& mo, py::handle q_, py::handle l) {
    return link_pose_of(LinkQuery(state_at(mo, q_, py::none()), l));
  }, model, q, link, (pose_doc + at_q).c_str());
  m.def("frame_position", [](const ModelPtr& mo, py::handle q_, py::handle l, py::handle p) {
    const Vec3 pt = to_vec3(p, "point");
    LinkQuery k(state_at(mo, q_, py::none()), l);
    return frame_position(k.model(), k.data, k.link, pt);
  }, model, q, link, py::arg("point"), (point_doc + at_q).c_str());
  m.def("frame_velocity", [](const ModelPtr& mo, py::handle q_, py::handle qd_, py::handle l,
                             py::handle p, py::handle f) {
    return frame_velocity_of(LinkQuery(state_at(mo, q_, qd_), l), p, f);
  }, model, q, qd, link, point, frame, (velocity_doc + at_qd).c_str());
  m.def("jacobian", [](const ModelPtr& mo, py::handle q_, py::handle l, py::handle p,
                       py::handle f) {
    return jacobian_of(LinkQuery(state_at(mo, q_, py::none()), l), p, f);
  }, model, q, link, point, frame, (jacobian_doc + at_q).c_str());
  m.def("jacobian_dot_times_qd", [](const ModelPtr& mo, py::handle q_, py::handle qd_,
                                    py::handle l, py::handle p, py::handle f) {
    return jacobian_dot_of(LinkQuery(state_at(mo, q_, qd_), l), p, f);
  }, model, q, qd, link, point, frame, (jdot_doc + at_qd).c_str());
  m.def("inverse_dynamics", [](const ModelPtr& mo, py::handle q_, py::handle qd_,
                               py::handle qdd) {
    return RobotQuery(state_at(mo, q_, qd_)).inverse_dynamics(qdd);
  }, model, q, qd, py::arg("qdd"), (id_doc + at_qd).c_str());
}

// Simulation(model, ..., stiffness, damping, drive_type): drives on every revolute and prismatic
// dof at construction, so that targets act from the first snippet on (set_drive_gains' rules).
void initial_drives(Simulation& s, py::handle stiffness, py::handle damping, py::handle type) {
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

// ---- names and the joint accessor (issue 20) --------------------------------------------------
// sim.joint(name) returns a JointAccessor: it holds the Simulation's Python object (so the
// simulation lives as long as it) and reads or writes the simulation at call time, under its lock.
// One-dof joints give floats, multi-dof joints arrays (or lists of settings).

/// A ValueError message for a name that is not among `names`: the nearest ones, or the valid ones.
std::string unknown_name(const std::string& what, const std::string& name,
                         const std::vector<std::string>& names) {
  const auto near = py::module_::import("difflib")
                        .attr("get_close_matches")(name, names, 3, 0.6)
                        .cast<std::vector<std::string>>();
  const bool some = !near.empty();
  const std::vector<std::string>& list = some ? near : names;
  std::string msg = "no " + what + " named '" + name + "'; " +
                    (some ? "did you mean: " : "the " + what + "s are: ");
  for (size_t i = 0; i < std::min<size_t>(list.size(), 12); ++i) msg += (i ? ", " : "") + list[i];
  if (list.size() > 12) msg += ", ... (" + std::to_string(list.size()) + " in all)";
  return msg;
}

struct JointAccessor {
  py::object owner;  // the Simulation's Python object
  Simulation* sim;
  int link;
  Link joint;  // a copy: its names and indices are every model variant's
  const Link& info() const { return joint; }
  int dof() const { return info().v_index; }

  /// f(sim, dof) for a one-dof joint, else [f(sim, dof) for each dof], under the lock.
  template <class F>
  py::object per_dof(F f) const {
    const Link& l = info();
    return locked(*sim, [&]() -> py::object {
      if (l.nv == 1) return py::cast(std::invoke(f, *sim, l.v_index));
      py::list out;
      for (int k = 0; k < l.nv; ++k) out.append(py::cast(std::invoke(f, *sim, l.v_index + k)));
      return out;
    });
  }
  /// The joint's entries of an (nv,) vector: a float or a new array.
  py::object slice(VecView (Simulation::*v)() const) const {
    const Link& l = info();
    return locked(*sim, [&]() -> py::object {
      if (l.nv == 1) return py::float_((sim->*v)()[l.v_index]);
      return py::cast(VecX((sim->*v)().segment(l.v_index, l.nv)));
    });
  }
};

JointAccessor joint_accessor(py::object sim_obj, py::handle joint) {
  Simulation& s = sim_obj.cast<Simulation&>();
  const std::string name = to_str(joint, "joint");
  const std::shared_ptr<const Model> model = model_of(s);
  std::vector<std::string> moving;
  for (int i = 0; i < model->num_links(); ++i) {
    const Link& l = model->links[static_cast<size_t>(i)];
    if (l.joint_name == name && l.nv == 0)
      throw std::invalid_argument("joint '" + name + "' is fixed: it has no degree of freedom");
    if (l.joint_name == name) return JointAccessor{std::move(sim_obj), &s, i, l};
    if (l.nv > 0) moving.push_back(l.joint_name);
  }
  throw std::invalid_argument(unknown_name("joint", name, moving));
}

py::array int_array(const std::vector<int>& v) {
  py::array_t<long long> a(static_cast<py::ssize_t>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) a.mutable_data()[i] = v[i];
  a.attr("flags").attr("writeable") = false;
  return a;
}

void bind_names(py::module_& m) {
  auto model = py::reinterpret_borrow<py::class_<Model, ModelPtr>>(m.attr("Model"));
  model.def_property_readonly("link_names", [](const Model& mo) {
        std::vector<std::string> names;
        for (const Link& l : mo.links) names.push_back(l.name);
        return names;
      }, "Link names in link order (depth-first preorder; a new list).")
      .def_property_readonly("joint_names", [](const Model& mo) {
        std::vector<std::string> names;
        for (const Link& l : mo.links) names.push_back(l.joint_name);
        return names;
      }, "Each link's inbound joint name, in link order (the root's joint first; a new list).");
  auto robot = py::reinterpret_borrow<py::class_<UrdfRobot>>(m.attr("UrdfRobot"));
  robot.def_property_readonly("urdf_joint_names", [](const UrdfRobot& r) { return r.joint_order; },
                              "Every <joint> name in file order, fixed ones included.")
      .def_property_readonly("dof_of_urdf_joint",
                             [](const UrdfRobot& r) { return int_array(r.dof_of_urdf_joint); },
                             "First dof of each urdf_joint_names entry, -1 for a fixed joint.")
      .def_property_readonly("link_of_urdf_joint",
                             [](const UrdfRobot& r) { return int_array(r.link_of_urdf_joint); },
                             "Model link of each joint's child (fixed: the link it merged into).")
      .def_property_readonly("urdf_joint_of_dof",
                             [](const UrdfRobot& r) { return int_array(r.urdf_joint_of_dof); },
                             "Index in urdf_joint_names of each dof's joint, -1 for a floating "
                             "root's dofs.");

  py::class_<JointAccessor> joint(m, "JointAccessor",
                            "One joint of a Simulation by name (Simulation.joint): reads and "
                            "writes the simulation at call time. One-dof joints give floats, "
                            "multi-dof joints arrays or lists.");
  joint.def_property_readonly("name", [](const JointAccessor& j) { return j.info().joint_name; },
                             "joint name")
      .def_property_readonly("type", [](const JointAccessor& j) { return j.info().joint_type; },
                             "JointType")
      .def_property_readonly("dof", [](const JointAccessor& j) { return j.info().v_index; },
                             "first dof index (into qd and the forces)")
      .def_property_readonly("nv", [](const JointAccessor& j) { return j.info().nv; }, "dofs")
      .def_property_readonly("link", [](const JointAccessor& j) { return j.link; },
                             "index of the joint's child link")
      .def_property_readonly("q", [](const JointAccessor& j) -> py::object {
            const Link& l = j.info();
            return locked(*j.sim, [&]() -> py::object {
              if (l.nq == 1) return py::float_(j.sim->q()[l.q_index]);
              return py::cast(VecX(j.sim->q().segment(l.q_index, l.nq)));
            });
          }, "position (float) or the joint's q entries (a new array)")
      .def("set_target", [](JointAccessor& j, double position, double velocity) {
             locked(*j.sim, [&] { j.sim->set_drive_target(j.dof(), position, velocity); });
           }, py::arg("position"), py::arg("velocity") = 0.0,
           "Sets the drive's target; ValueError if the joint has no drive.")
      .def_property("drive",
                    [](const JointAccessor& j) { return j.per_dof(&Simulation::drive); },
                    [](JointAccessor& j, const Drive& d) {
                      locked(*j.sim, [&] { j.sim->set_drive(j.dof(), d); });
                    },
                    "the Drive (a copy); assign a Drive to set it")
      .def_property("limits",
                    [](const JointAccessor& j) {
                      return j.per_dof([](const Simulation& s, int d) {
                        return std::make_pair(s.lower_limit(d), s.upper_limit(d));
                      });
                    },
                    [](JointAccessor& j, std::pair<double, double> l) {
                      locked(*j.sim, [&] { j.sim->set_joint_limits(j.dof(), l.first, l.second); });
                    },
                    "(lower, upper) position limits; assign a pair to set them (+-inf: none)")
      .def_property("friction",
                    [](const JointAccessor& j) { return j.per_dof(&Simulation::joint_friction); },
                    [](JointAccessor& j, const JointFriction& f) {
                      locked(*j.sim, [&] { j.sim->set_joint_friction(j.dof(), f); });
                    },
                    "the JointFriction (a copy); assign one to set it")
      .def_property("max_velocity",
                    [](const JointAccessor& j) {
                      return j.per_dof(&Simulation::max_joint_velocity);
                    },
                    [](JointAccessor& j, double v) {
                      locked(*j.sim, [&] { j.sim->set_max_joint_velocity(j.dof(), v); });
                    },
                    "largest |qd| (inf: none)")
      .def("__repr__", [](const JointAccessor& j) {
        return "JointAccessor('" + j.info().joint_name + "', " + to_string(j.info().joint_type) +
               ", dof " + std::to_string(j.info().v_index) + ")";
      });
  using Vector = VecView (Simulation::*)() const;
  for (const auto& [name, vector] : {std::pair<const char*, Vector>{"qd", &Simulation::qd},
                                     {"drive_force", &Simulation::drive_force},
                                     {"limit_force", &Simulation::limit_force},
                                     {"friction_force", &Simulation::friction_force},
                                     {"applied_force", &Simulation::applied_force}})
    joint.def_property_readonly(name, [v = vector](const JointAccessor& j) { return j.slice(v); },
                                "the joint's entries of the simulation's vector of that name "
                                "(a float, or a new array), read now");

  m.def("example_path", [](py::handle name) {
        const std::string n = to_str(name, "name");
        const auto os = py::module_::import("os");
        const py::object dir = os.attr("path").attr("join")(
            os.attr("path").attr("dirname")(py::module_::import("featherdrive").attr("__file__")),
            "examples");
        const auto robots = py::module_::import("builtins")
                                .attr("sorted")(os.attr("listdir")(dir))
                                .cast<std::vector<std::string>>();
        if (std::find(robots.begin(), robots.end(), n) == robots.end())
          throw std::invalid_argument("example_path: " + unknown_name("example robot", n, robots));
        return os.attr("path").attr("join")(dir, n).cast<std::string>();
      }, py::arg("name"),
      "The path of an example robot (examples/NAME, copied beside the module when it was built), "
      "e.g. example_path('arm7.urdf'); ValueError naming the ones there are.");

  auto sim = py::reinterpret_borrow<py::class_<Simulation, SimulationHolder>>(m.attr("Simulation"));
  sim.def("joint", &joint_accessor, py::arg("name"),
          "A live accessor of the named joint (q, qd, forces, drive, set_target, limits, friction, "
          "max_velocity); ValueError naming the nearest joint names for an unknown one.");
}

}  // namespace

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
  py::register_exception<DivergenceError>(m, "DivergenceError", PyExc_RuntimeError)
      .doc() = "A step would produce a non-finite value; the simulation keeps its state from "
               "before that step. A RuntimeError.";
  py::register_exception<ModelError>(m, "ModelError", PyExc_ValueError).doc() =
      "Bad model input (ModelBuilder): names the link or joint, field and value. A ValueError.";
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError).doc() =
      "A bad input file (URDF, scene): names the file, element or key and value. A ValueError.";

  // ---- enums ----------------------------------------------------------------------------------
  py::enum_<JointType>(m, "JointType", "The type of a link's inbound joint.")
      .value("fixed", JointType::fixed, "welds the link to its parent, 0 dofs")
      .value("revolute", JointType::revolute, "rotation about the axis, 1 dof")
      .value("prismatic", JointType::prismatic, "translation along the axis, 1 dof")
      .value("spherical", JointType::spherical, "free rotation: nq = 4 (quaternion), nv = 3")
      .value("floating", JointType::floating, "root only: nq = 7, nv = 6");
  py::enum_<DriveType>(m, "DriveType", "The kind of a joint drive.")
      .value("none", DriveType::none, "no drive on this dof")
      .value("force", DriveType::force, "stiffness in N/m or Nm/rad, damping in Ns/m or Nms/rad")
      .value("acceleration", DriveType::acceleration,
             "stiffness in 1/s^2, damping in 1/s: a mass-free response");
  py::enum_<SolverType>(m, "SolverType", "The constraint solver.")
      .value("pgs", SolverType::pgs, "projected Gauss-Seidel")
      .value("tgs", SolverType::tgs, "temporal Gauss-Seidel (sub-stepped)");

  // ---- settings structs -----------------------------------------------------------------------
  py::class_<Drive>(m, "Drive", "A drive's settings (all of them may change between steps).")
      .def(py::init([](py::handle type, double stiffness, double damping, double max_force,
                       double target_position, double target_velocity, double max_impulse) {
             Drive d;
             d.type = to_drive_type(type);
             d.stiffness = stiffness;
             d.damping = damping;
             d.max_force = max_force;
             d.target_position = target_position;
             d.target_velocity = target_velocity;
             d.max_impulse = max_impulse;
             return d;
           }),
           py::arg("type") = DriveType::force, py::arg("stiffness") = 0.0,
           py::arg("damping") = 0.0, py::arg("max_force") = kInf,
           py::arg("target_position") = 0.0, py::arg("target_velocity") = 0.0,
           py::arg("max_impulse") = kInf,
           "A drive; type is a DriveType or 'none' | 'force' | 'acceleration'. Checked when "
           "given to Simulation.set_drive.")
      .def_readwrite("type", &Drive::type, "DriveType")
      .def_readwrite("stiffness", &Drive::stiffness, "N/m or Nm/rad (force), 1/s^2 (acceleration)")
      .def_readwrite("damping", &Drive::damping, "Ns/m or Nms/rad (force), 1/s (acceleration)")
      .def_readwrite("max_force", &Drive::max_force,
                     "largest drive force; the step's impulse is limited to max_force * dt")
      .def_readwrite("target_position", &Drive::target_position, "target position (m or rad)")
      .def_readwrite("target_velocity", &Drive::target_velocity, "target velocity (m/s or rad/s)")
      .def_readwrite("max_impulse", &Drive::max_impulse,
                     "largest drive impulse of a step; set at most one of max_force, max_impulse")
      .def("__repr__", [](const Drive& d) {
        return std::string("Drive(type='") + to_string(d.type) + "', stiffness=" + fmt(d.stiffness) +
               ", damping=" + fmt(d.damping) + ", max_force=" + fmt(d.max_force) +
               ", target_position=" + fmt(d.target_position) + ", target_velocity=" +
               fmt(d.target_velocity) + ", max_impulse=" + fmt(d.max_impulse) + ")";
      });

  py::class_<JointFriction>(m, "JointFriction",
                            "Joint friction: static and dynamic efforts (N or Nm) and viscous "
                            "friction (Ns/m or Nms/rad).")
      .def(py::init([](double s, double d, double v) { return JointFriction{s, d, v}; }),
           py::arg("static_effort") = 0.0, py::arg("dynamic_effort") = 0.0,
           py::arg("viscous") = 0.0, "Joint friction settings.")
      .def_readwrite("static_effort", &JointFriction::static_effort, "N or Nm")
      .def_readwrite("dynamic_effort", &JointFriction::dynamic_effort, "N or Nm")
      .def_readwrite("viscous", &JointFriction::viscous, "Ns/m or Nms/rad")
      .def("active", &JointFriction::active, "Whether any friction is set.");

  py::class_<ActuatorEnvelope>(m, "ActuatorEnvelope",
                               "A DC-motor-like limit on a drive's effort (none while "
                               "max_effort = 0).")
      .def(py::init([](double max_effort, double max_actuator_velocity, double gradient,
                       double resistance) {
             return ActuatorEnvelope{max_effort, max_actuator_velocity, gradient, resistance};
           }),
           py::arg("max_effort") = 0.0, py::arg("max_actuator_velocity") = kInf,
           py::arg("speed_effort_gradient") = 0.0, py::arg("velocity_dependent_resistance") = 0.0,
           "An actuator envelope.")
      .def_readwrite("max_effort", &ActuatorEnvelope::max_effort, "N or Nm; 0 = no envelope")
      .def_readwrite("max_actuator_velocity", &ActuatorEnvelope::max_actuator_velocity,
                     "m/s or rad/s")
      .def_readwrite("speed_effort_gradient", &ActuatorEnvelope::speed_effort_gradient,
                     "effort lost per unit speed")
      .def_readwrite("velocity_dependent_resistance",
                     &ActuatorEnvelope::velocity_dependent_resistance,
                     "opposing effort per unit speed")
      .def("active", &ActuatorEnvelope::active, "Whether the envelope limits the drive.");

  // Explicit actuators (docs/math/explicit_actuators.md): one class with a kind, and a factory
  // per Isaac Lab model with keyword arguments.
  py::enum_<ActuatorKind>(m, "ActuatorKind", "Which explicit actuator model (Isaac Lab's).")
      .value("none", ActuatorKind::none, "no explicit actuator")
      .value("ideal_pd", ActuatorKind::ideal_pd, "IdealPDActuator: PD clipped to effort_limit")
      .value("dc_motor", ActuatorKind::dc_motor, "DCMotor: within the torque-speed line")
      .value("remotized_pd", ActuatorKind::remotized_pd,
             "RemotizedPDActuator: within a position-dependent limit");
  py::class_<ExplicitActuator>(m, "ExplicitActuator",
                               "An explicit actuator of one joint; checked when given to "
                               "Simulation.set_actuator.")
      .def(py::init([](py::handle kind, double kp, double kd, double effort_limit, double sat,
                       double speed, py::handle lookup, py::handle delay) {
             return make_actuator(to_actuator_kind(kind), kp, kd, effort_limit, sat, speed,
                                  lookup, delay);
           }),
           py::arg("kind") = ActuatorKind::ideal_pd, py::kw_only(), py::arg("stiffness") = 0.0,
           py::arg("damping") = 0.0, py::arg("effort_limit") = kInf,
           py::arg("saturation_effort") = 0.0, py::arg("velocity_limit") = 0.0,
           py::arg("lookup") = py::none(), py::arg("delay") = 0,
           "kind: an ActuatorKind or its name; lookup: (n, 2) rows of (position, max effort).")
      .def_readwrite("kind", &ExplicitActuator::kind, "ActuatorKind")
      .def_readwrite("stiffness", &ExplicitActuator::stiffness, "N/m or Nm/rad")
      .def_readwrite("damping", &ExplicitActuator::damping, "Ns/m or Nms/rad")
      .def_readwrite("effort_limit", &ExplicitActuator::effort_limit,
                     "the actuator's clip (N or Nm), apart from a drive's max_force")
      .def_readwrite("saturation_effort", &ExplicitActuator::saturation_effort,
                     "dc_motor: stall effort")
      .def_readwrite("velocity_limit", &ExplicitActuator::velocity_limit,
                     "dc_motor: no-load speed")
      .def_property(
          "lookup",
          [](const ExplicitActuator& a) {
            RowMatrix t(static_cast<Eigen::Index>(a.lookup.size()), 2);
            for (size_t i = 0; i < a.lookup.size(); ++i)
              t.row(static_cast<Eigen::Index>(i)) << a.lookup[i].first, a.lookup[i].second;
            return read_only(std::move(t));
          },
          [](ExplicitActuator& a, py::handle t) { a.lookup = to_lookup(t); },
          "remotized_pd: (n, 2) rows of (position, max effort) (a copy)")
      .def_property(
          "delay", [](const ExplicitActuator& a) { return a.delay; },
          [](ExplicitActuator& a, py::handle d) {
            a.delay = to_int(d, "delay", 0, kMaxActuatorDelay);
          },
          "physics steps between a command and its effort")
      .def("__repr__", [](const ExplicitActuator& a) {
        return std::string("ExplicitActuator('") + to_string(a.kind) + "', stiffness=" +
               fmt(a.stiffness) + ", damping=" + fmt(a.damping) + ", effort_limit=" +
               fmt(a.effort_limit) + ", saturation_effort=" + fmt(a.saturation_effort) +
               ", velocity_limit=" + fmt(a.velocity_limit) + ", lookup=" +
               std::to_string(a.lookup.size()) + " points, delay=" + std::to_string(a.delay) + ")";
      });
  m.def(
      "IdealPD",
      [](double kp, double kd, double effort_limit, py::handle delay) {
        return make_actuator(ActuatorKind::ideal_pd, kp, kd, effort_limit, 0.0, 0.0, py::none(),
                             delay);
      },
      py::kw_only(), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0,
      py::arg("effort_limit") = kInf, py::arg("delay") = 0,
      "Isaac Lab's IdealPDActuator (DelayedPDActuator with a delay): an ExplicitActuator.");
  m.def(
      "DCMotor",
      [](double kp, double kd, double effort_limit, double sat, double speed, py::handle delay) {
        return make_actuator(ActuatorKind::dc_motor, kp, kd, effort_limit, sat, speed,
                             py::none(), delay);
      },
      py::kw_only(), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0,
      py::arg("effort_limit") = kInf, py::arg("saturation_effort"), py::arg("velocity_limit"),
      py::arg("delay") = 0, "Isaac Lab's DCMotor: an ExplicitActuator.");
  m.def(
      "RemotizedPD",
      [](double kp, double kd, py::handle lookup, double effort_limit, py::handle delay) {
        return make_actuator(ActuatorKind::remotized_pd, kp, kd, effort_limit, 0.0, 0.0, lookup,
                             delay);
      },
      py::kw_only(), py::arg("stiffness") = 0.0, py::arg("damping") = 0.0, py::arg("lookup"),
      py::arg("effort_limit") = kInf, py::arg("delay") = 0,
      "Isaac Lab's RemotizedPDActuator: an ExplicitActuator; lookup (n, 2) rows of (position, "
      "max effort).");

  py::enum_<Compat>(m, "Compat", "Whose defaults and step details a simulation follows.")
      .value("none", Compat::none, "featherdrive's ideal articulation")
      .value("physx", Compat::physx, "PhysX 5.6.1's defaults (docs/physx_parity.md)");

  py::class_<LinkParameters>(m, "LinkParameters",
                             "PhysX's per-link parameters: cfm scale, linear and angular damping "
                             "[1/s], max linear [m/s] and angular [rad/s] velocity.")
      .def(py::init([](double cfm, double ld, double ad, double mlv, double mav) {
             return LinkParameters{cfm, ld, ad, mlv, mav};
           }),
           py::arg("cfm_scale") = 0.0, py::arg("linear_damping") = 0.0,
           py::arg("angular_damping") = 0.0, py::arg("max_linear_velocity") = kInf,
           py::arg("max_angular_velocity") = kInf, "Link parameters (inert by default).")
      .def_readwrite("cfm_scale", &LinkParameters::cfm_scale, "in [0, 1]")
      .def_readwrite("linear_damping", &LinkParameters::linear_damping, "1/s")
      .def_readwrite("angular_damping", &LinkParameters::angular_damping, "1/s")
      .def_readwrite("max_linear_velocity", &LinkParameters::max_linear_velocity, "m/s; inf for none")
      .def_readwrite("max_angular_velocity", &LinkParameters::max_angular_velocity,
                     "rad/s; inf for none")
      .def("__repr__", [](const LinkParameters& p) {
        std::string s = "LinkParameters(cfm_scale=";
        s += fmt(p.cfm_scale);
        s += ", linear_damping=";
        s += fmt(p.linear_damping);
        s += ", angular_damping=";
        s += fmt(p.angular_damping);
        s += ", max_linear_velocity=";
        s += fmt(p.max_linear_velocity);
        s += ", max_angular_velocity=";
        s += fmt(p.max_angular_velocity);
        s += ")";
        return s;
      });

  py::class_<SimulationOptions>(m, "SimulationOptions", "Time step and solver settings.")
      .def(py::init(&make_options), py::arg("dt") = 1.0 / 60.0, py::arg("solver") = "pgs",
           py::arg("position_iterations") = 4, py::arg("velocity_iterations") = 1,
           py::arg("compat") = "none",
           "Options; solver is 'pgs' or 'tgs'. Raises ValueError for dt <= 0, "
           "position_iterations < 1 or velocity_iterations < 0.")
      .def_readwrite("dt", &SimulationOptions::dt, "time step [s]")
      .def_readwrite("solver", &SimulationOptions::solver, "SolverType")
      .def_property(
          "position_iterations", [](const SimulationOptions& o) { return o.position_iterations; },
          [](SimulationOptions& o, py::handle n) {
            o.position_iterations = to_int(n, "position_iterations", 1);
          },
          ">= 1")
      .def_property(
          "velocity_iterations", [](const SimulationOptions& o) { return o.velocity_iterations; },
          [](SimulationOptions& o, py::handle n) {
            o.velocity_iterations = to_int(n, "velocity_iterations", 0);
          },
          ">= 0")
      .def_readwrite("compat", &SimulationOptions::compat, "Compat, chosen at construction")
      .def("__repr__", [](const SimulationOptions& o) {
        return "SimulationOptions(dt=" + fmt(o.dt) + ", solver='" + to_string(o.solver) +
               "', position_iterations=" + std::to_string(o.position_iterations) +
               ", velocity_iterations=" + std::to_string(o.velocity_iterations) + ")";
      });
  m.def("validate_options", &validate_options, py::arg("options"),
        "Raises ValueError naming the field and value for bad options.");

  // ---- model ----------------------------------------------------------------------------------
  py::class_<Link>(m, "Link", "A link of a Model and its inbound joint (read-only).")
      .def_readonly("name", &Link::name, "link name")
      .def_readonly("parent", &Link::parent, "index of the parent link, -1 for the world")
      .def_readonly("children", &Link::children, "indices of the child links")
      .def_readonly("mass", &Link::mass, "kg")
      .def_readonly("com", &Link::com, "centre of mass in the link frame (3,)")
      .def_readonly("inertia_com", &Link::inertia_com, "inertia about the centre of mass (3, 3)")
      .def_readonly("joint_name", &Link::joint_name, "name of the inbound joint")
      .def_readonly("joint_type", &Link::joint_type, "JointType of the inbound joint")
      .def_readonly("axis", &Link::axis, "unit joint axis in the joint frame (3,)")
      .def_readonly("q_index", &Link::q_index, "first entry of this joint in q")
      .def_readonly("v_index", &Link::v_index, "first entry of this joint in qd")
      .def_readonly("nq", &Link::nq, "entries of this joint in q")
      .def_readonly("nv", &Link::nv, "dofs of this joint")
      .def_readonly("subtree_end", &Link::subtree_end, "links [index, subtree_end) are its subtree")
      .def("__repr__", [](const Link& l) {
        return "Link('" + l.name + "', joint='" + l.joint_name + "', " + to_string(l.joint_type) + ")";
      });

  py::class_<Model, ModelPtr>(m, "Model",
                              "The immutable description of an articulation; one Model serves "
                              "many simulations.")
      .def_readonly("nq", &Model::nq, "size of the configuration vector q")
      .def_readonly("nv", &Model::nv, "number of dofs (size of qd)")
      .def_readonly("gravity", &Model::gravity, "gravity (3,) [m/s^2]")
      .def_readonly("links", &Model::links, "the links in depth-first preorder (list of Link)")
      .def_readonly("armature", &Model::armature, "per dof (nv,)")
      .def_readonly("lower_limit", &Model::lower_limit, "per dof (nv,); -inf where unbounded")
      .def_readonly("upper_limit", &Model::upper_limit, "per dof (nv,); +inf where unbounded")
      .def_readonly("effort_limit", &Model::effort_limit, "per dof (nv,); informative")
      .def_readonly("velocity_limit", &Model::velocity_limit, "per dof (nv,)")
      .def_readonly("damping", &Model::damping, "viscous joint damping per dof (nv,)")
      .def_readonly("friction", &Model::friction, "Coulomb joint friction per dof (nv,)")
      .def_readonly("dof_link", &Model::dof_link, "the link owning each dof")
      .def_readonly("dof_names", &Model::dof_names,
                    "joint name of each dof ('joint:wx' etc. for multi-dof joints)")
      .def("floating_base", &Model::floating_base, "Whether the root has a floating joint.")
      .def("num_links", &Model::num_links, "Number of links.")
      .def("link_index", &Model::link_index, py::arg("name"),
           "Index of the named link; ValueError if there is none.")
      .def("joint_link_index", &Model::joint_link_index, py::arg("joint_name"),
           "Index of the link whose inbound joint has this name; ValueError if there is none.")
      .def("dof_index", &Model::dof_index, py::arg("joint_name"),
           "First dof of the named joint; ValueError if there is none or it has no dofs.")
      .def("neutral_configuration", &Model::neutral_configuration,
           "q with every joint at its reference (nq,).")
      .def("__repr__", [](const Model& mo) {
        return "Model(links=" + std::to_string(mo.num_links()) + ", nq=" + std::to_string(mo.nq) +
               ", nv=" + std::to_string(mo.nv) + ")";
      });

  py::class_<JointSpec>(m, "JointSpec",
                        "The inbound joint of a link, as in URDF (see revolute_joint etc.).")
      .def(py::init<>(), "A fixed joint at the parent's origin.")
      .def_readwrite("name", &JointSpec::name, "joint name")
      .def_readwrite("type", &JointSpec::type, "JointType")
      .def_property(
          "origin_xyz", [](const JointSpec& j) { return j.origin_xyz; },
          [](JointSpec& j, py::handle v) { j.origin_xyz = to_vec3(v, "origin_xyz"); },
          "joint frame position in the parent link frame (3,)")
      .def_property(
          "origin_rpy", [](const JointSpec& j) { return j.origin_rpy; },
          [](JointSpec& j, py::handle v) { j.origin_rpy = to_vec3(v, "origin_rpy"); },
          "joint frame roll, pitch, yaw in the parent link frame (3,)")
      .def_property(
          "axis", [](const JointSpec& j) { return j.axis; },
          [](JointSpec& j, py::handle v) { j.axis = to_vec3(v, "axis"); },
          "axis in the joint frame (3,), not zero")
      .def_readwrite("armature", &JointSpec::armature,
                     "[] (none), [a] (every dof) or one value per dof")
      .def_readwrite("lower_limit", &JointSpec::lower_limit, "m or rad; -inf for none")
      .def_readwrite("upper_limit", &JointSpec::upper_limit, "m or rad; +inf for none")
      .def_readwrite("effort_limit", &JointSpec::effort_limit, "N or Nm (informative)")
      .def_readwrite("velocity_limit", &JointSpec::velocity_limit, "m/s or rad/s")
      .def_readwrite("damping", &JointSpec::damping, "viscous joint damping")
      .def_readwrite("friction", &JointSpec::friction, "Coulomb joint friction");

  py::class_<LinkSpec>(m, "LinkSpec", "A link description for ModelBuilder (see make_link).")
      .def(py::init<>(), "An empty link description.")
      .def_readwrite("name", &LinkSpec::name, "link name")
      .def_readwrite("parent", &LinkSpec::parent, "parent link name, '' for the root")
      .def_readwrite("mass", &LinkSpec::mass, "kg")
      .def_property(
          "com", [](const LinkSpec& l) { return l.com; },
          [](LinkSpec& l, py::handle v) { l.com = to_vec3(v, "com"); },
          "centre of mass in the link frame (3,)")
      .def_property(
          "inertia", [](const LinkSpec& l) { return l.inertia; },
          [](LinkSpec& l, py::handle v) { l.inertia = to_mat3(v, "inertia"); },
          "inertia tensor about the centre of mass, link axes (3, 3)")
      .def_readwrite("joint", &LinkSpec::joint, "the inbound JointSpec");

  const auto zero3 = py::make_tuple(0.0, 0.0, 0.0);
  m.def("fixed_joint",
        [](std::string name, py::handle xyz, py::handle rpy) {
          return fixed_joint(std::move(name), to_vec3(xyz, "xyz"), to_vec3(rpy, "rpy"));
        },
        py::arg("name"), py::arg("xyz") = zero3, py::arg("rpy") = zero3, "A fixed JointSpec.");
  m.def("revolute_joint",
        [](std::string name, py::handle axis, py::handle xyz, py::handle rpy) {
          return revolute_joint(std::move(name), to_vec3(axis, "axis"), to_vec3(xyz, "xyz"),
                                to_vec3(rpy, "rpy"));
        },
        py::arg("name"), py::arg("axis"), py::arg("xyz") = zero3, py::arg("rpy") = zero3,
        "A revolute JointSpec about axis (3,) at origin (xyz, rpy).");
  m.def("prismatic_joint",
        [](std::string name, py::handle axis, py::handle xyz, py::handle rpy) {
          return prismatic_joint(std::move(name), to_vec3(axis, "axis"), to_vec3(xyz, "xyz"),
                                 to_vec3(rpy, "rpy"));
        },
        py::arg("name"), py::arg("axis"), py::arg("xyz") = zero3, py::arg("rpy") = zero3,
        "A prismatic JointSpec along axis (3,) at origin (xyz, rpy).");
  m.def("spherical_joint",
        [](std::string name, py::handle xyz, py::handle rpy) {
          return spherical_joint(std::move(name), to_vec3(xyz, "xyz"), to_vec3(rpy, "rpy"));
        },
        py::arg("name"), py::arg("xyz") = zero3, py::arg("rpy") = zero3, "A spherical JointSpec.");
  m.def("floating_joint", &floating_joint, py::arg("name"), "A floating JointSpec (root only).");
  m.def("make_link",
        [](std::string name, std::string parent, double mass, py::handle com, py::handle inertia,
           JointSpec joint) {
          return make_link(std::move(name), std::move(parent), mass, to_vec3(com, "com"),
                           to_mat3(inertia, "inertia"), std::move(joint));
        },
        py::arg("name"), py::arg("parent"), py::arg("mass"), py::arg("com"), py::arg("inertia"),
        py::arg("joint"),
        "A LinkSpec: mass, centre of mass (3,), inertia about it (3, 3) and inbound joint; "
        "parent '' for the root.");

  py::class_<ModelBuilder>(m, "ModelBuilder", "Builds a Model from LinkSpecs, validating once.")
      .def(py::init<>(), "An empty builder; gravity (0, 0, -9.81).")
      .def(
          "set_gravity",
          [](ModelBuilder& b, py::handle g) -> ModelBuilder& {
            return b.set_gravity(to_vec3(g, "gravity"));
          },
          py::arg("gravity"), ref, "Sets gravity (3,); returns the builder.")
      .def("add_link", &ModelBuilder::add_link, py::arg("link"), ref,
           "Adds a LinkSpec; returns the builder.")
      .def(
          "build", [](const ModelBuilder& b) { return std::make_shared<Model>(b.build()); },
          "Validates everything and returns the Model; ModelError (a ValueError) naming the "
          "link or joint, field and value.");

  // ---- simulation -----------------------------------------------------------------------------
  // Every method holds the object's lock (see Hold) while it reads or writes the simulation, and
  // converts its Python arguments before (a conversion may run Python code that uses the object).
  // The views (q, qd, ...) are taken without it: creating one reads nothing.
  py::class_<Simulation, SimulationHolder>(m, "Simulation",
                                           "One simulation of a Model: state, drives, joint "
                                           "settings and the forces of the last step.")
      .def(py::init([](ModelPtr model, double dt, py::handle solver, py::handle pi, py::handle vi,
                       py::handle compat, py::handle kp, py::handle kd, py::handle type) {
             Simulation s(std::move(model), make_options(dt, solver, pi, vi, compat));
             initial_drives(s, kp, kd, type);
             return s;
           }),
           py::arg("model"), py::arg("dt") = 1.0 / 60.0, py::arg("solver") = "pgs",
           py::arg("position_iterations") = 4, py::arg("velocity_iterations") = 1,
           py::arg("compat") = "none", py::arg("stiffness") = py::none(),
           py::arg("damping") = py::none(), py::arg("drive_type") = "force",
           (std::string("A simulation at the neutral configuration, at rest; solver ") +
            kSolverDoc + ". Given stiffness or damping (a scalar for every revolute and "
            "prismatic dof, or (nv,) with 0 on other dofs), every such dof gets a drive of "
            "drive_type ('force' or 'acceleration'); else no dof has a drive.").c_str())
      .def(py::init([](ModelPtr model, const SimulationOptions& o) {
             return Simulation(std::move(model), o);
           }),
           py::arg("model"), py::arg("options"), "A simulation with these options.")
      .def("copy", [](const Simulation& s) { return locked(s, [&] { return Simulation(s); }); },
           "An independent copy (same model, state and settings).")
      .def_property_readonly("model", [](const Simulation& s) { return to_python(model_of(s)); },
                             "The Model.")
      .def_property_readonly(
          "options", [](const Simulation& s) { return locked(s, [&] { return s.options(); }); },
          "The SimulationOptions (a copy; set_options changes them).")
      .def(
          "set_options",
          [](Simulation& s, const SimulationOptions& o) { locked(s, [&] { s.set_options(o); }); },
          py::arg("options"), "Replaces the options; ValueError for bad ones.")
      .def_property_readonly("q", &Simulation::q, ref, "Configuration (nq,), read-only view.")
      .def_property_readonly("qd", &Simulation::qd, ref, "Joint velocities (nv,), read-only view.")
      .def(
          "set_q",
          [](Simulation& s, py::handle q) {
            const VecX v = to_vector(q, model_of(s)->nq, "q");
            locked(s, [&] { s.set_q(v); });
          },
          py::arg("q"), "Sets the configuration (nq,); quaternions are normalised.")
      .def(
          "set_qd",
          [](Simulation& s, py::handle qd) {
            const VecX v = to_vector(qd, model_of(s)->nv, "qd");
            locked(s, [&] { s.set_qd(v); });
          },
          py::arg("qd"), "Sets the joint velocities (nv,).")
      .def_property_readonly(
          "time", [](const Simulation& s) { return locked(s, [&] { return s.time(); }); },
          "Simulated time [s].")
      .def_property_readonly(
          "step_count",
          [](const Simulation& s) { return locked(s, [&] { return s.step_count(); }); },
          "Steps made.")
      .def(
          "set_applied_force",
          [](Simulation& s, py::handle tau) {
            const VecX v = to_vector(tau, model_of(s)->nv, "applied_force");
            locked(s, [&] { s.set_applied_force(v); });
          },
          py::arg("tau"), "Joint forces applied through each step (nv,), e.g. feed-forward.")
      .def_property_readonly("applied_force", &Simulation::applied_force, ref,
                             "Applied joint forces (nv,), read-only view.")
      .def(
          "set_drive",
          [](Simulation& s, py::handle joint, const Drive& d) {
            on_joint(s, joint, [&](int dof) { s.set_drive(dof, d); });
          },
          py::arg("joint"), py::arg("drive"),
          "Sets the Drive of a joint (name) or dof (index); ValueError naming the joint and "
          "field for bad values.")
      .def(
          "drive",
          [](const Simulation& s, py::handle joint) {
            return on_joint(s, joint, [&](int dof) { return s.drive(dof); });
          },
          py::arg("joint"), "The Drive (a copy) of a joint (name) or dof (index).")
      .def(
          "set_drive_target",
          [](Simulation& s, py::handle joint, double position, double velocity) {
            on_joint(s, joint, [&](int dof) { s.set_drive_target(dof, position, velocity); });
          },
          py::arg("joint"), py::arg("position"), py::arg("velocity") = 0.0,
          "Sets one joint's drive target position and velocity.")
      .def(
          "set_drive_targets",
          [](Simulation& s, py::handle positions, py::object velocities) {
            const int nv = model_of(s)->nv;
            const VecX p = to_vector(positions, nv, "positions");
            const VecX v = velocities.is_none() ? VecX::Zero(nv) : to_vector(velocities, nv, "velocities");
            locked(s, [&] { set_drive_targets(s, p, v); });
          },
          py::arg("positions"), py::arg("velocities") = py::none(),
          "Sets every dof's target position and velocity (nv,) each; velocities default to 0. "
          "Nothing changes on a ValueError.")
      .def(
          "set_drive_gains",
          [](Simulation& s, py::handle stiffness, py::handle damping, py::handle type) {
            const int nv = model_of(s)->nv;
            const VecX kp = to_vector(stiffness, nv, "stiffness", true);
            const VecX kd = to_vector(damping, nv, "damping", true);
            const DriveType t = to_drive_type(type);
            locked(s, [&] { set_drive_gains(s, kp, kd, t); });
          },
          py::arg("stiffness"), py::arg("damping"), py::arg("type") = DriveType::force,
          "Sets every dof's stiffness and damping ((nv,) each, or a scalar for all) and makes "
          "the drives of revolute and prismatic joints `type` (default force), keeping "
          "max_force and targets. Other joints' dofs must get 0. Nothing changes on a ValueError.")
      .def(
          "set_joint_limits",
          [](Simulation& s, py::handle joint, double lower, double upper) {
            on_joint(s, joint, [&](int dof) { s.set_joint_limits(dof, lower, upper); });
          },
          py::arg("joint"), py::arg("lower"), py::arg("upper"),
          "Position limits of a revolute or prismatic joint (name or dof); +-inf for none.")
      .def(
          "lower_limit",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.lower_limit(dof); });
          },
          py::arg("joint"), "Lower position limit of a joint (name or dof).")
      .def(
          "upper_limit",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.upper_limit(dof); });
          },
          py::arg("joint"), "Upper position limit of a joint (name or dof).")
      .def(
          "set_joint_friction",
          [](Simulation& s, py::handle joint, const JointFriction& f) {
            on_joint(s, joint, [&](int dof) { s.set_joint_friction(dof, f); });
          },
          py::arg("joint"), py::arg("friction"), "JointFriction of a joint (name or dof).")
      .def(
          "joint_friction",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.joint_friction(dof); });
          },
          py::arg("joint"), "The JointFriction (a copy) of a joint (name or dof).")
      .def(
          "set_max_joint_velocity",
          [](Simulation& s, py::handle joint, double v) {
            on_joint(s, joint, [&](int dof) { s.set_max_joint_velocity(dof, v); });
          },
          py::arg("joint"), py::arg("max_velocity"),
          "Largest |qd| of a joint (name or dof); inf for none.")
      .def(
          "max_joint_velocity",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.max_joint_velocity(dof); });
          },
          py::arg("joint"), "Largest |qd| of a joint (name or dof).")
      .def(
          "set_friction_coefficient",
          [](Simulation& s, py::handle joint, double c) {
            on_joint(s, joint, [&](int dof) { s.set_friction_coefficient(dof, c); });
          },
          py::arg("joint"), py::arg("coefficient"),
          "PhysX's older joint friction coefficient of a joint (name or dof): the friction impulse "
          "of a solve is at most coefficient * h * |F|, F the force the joint transmits.")
      .def(
          "friction_coefficient",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.friction_coefficient(dof); });
          },
          py::arg("joint"), "The friction coefficient of a joint (name or dof).")
      .def(
          "set_link_parameters",
          [](Simulation& s, py::handle link, const LinkParameters& p) {
            const NameOrIndex l = link_arg(link);
            locked(s, [&] { s.set_link_parameters(link_of(s.model(), l), p); });
          },
          py::arg("link"), py::arg("parameters"), "LinkParameters of a link (name or index).")
      .def(
          "link_parameters",
          [](const Simulation& s, py::handle link) {
            const NameOrIndex l = link_arg(link);
            return locked(s, [&] { return s.link_parameters(link_of(s.model(), l)); });
          },
          py::arg("link"), "The LinkParameters (a copy) of a link (name or index).")
      .def(
          "set_actuator_envelope",
          [](Simulation& s, py::handle joint, const ActuatorEnvelope& e) {
            on_joint(s, joint, [&](int dof) { s.set_actuator_envelope(dof, e); });
          },
          py::arg("joint"), py::arg("envelope"), "ActuatorEnvelope of a joint (name or dof).")
      .def(
          "actuator_envelope",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.actuator_envelope(dof); });
          },
          py::arg("joint"), "The ActuatorEnvelope (a copy) of a joint (name or dof).")
      .def(
          "set_actuator",
          [](Simulation& s, py::handle joint, const ExplicitActuator& a) {
            on_joint(s, joint, [&](int dof) { s.set_actuator(dof, a); });
          },
          py::arg("joint"), py::arg("actuator"),
          "Sets the ExplicitActuator of a joint (name or dof; kind 'none' clears it) and empties "
          "its delay history. ValueError beside a drive whose type is not 'none'.")
      .def(
          "actuator",
          [](const Simulation& s, py::handle j) {
            return on_joint(s, j, [&](int dof) { return s.actuator(dof); });
          },
          py::arg("joint"), "The ExplicitActuator (a copy) of a joint (name or dof).")
      .def(
          "clear_actuator",
          [](Simulation& s, py::handle j) {
            on_joint(s, j, [&](int dof) { s.clear_actuator(dof); });
          },
          py::arg("joint"), "Removes a joint's explicit actuator.")
      .def(
          "set_actuator_feedforward",
          [](Simulation& s, py::handle j, double effort) {
            on_joint(s, j, [&](int dof) { s.set_actuator_feedforward(dof, effort); });
          },
          py::arg("joint"), py::arg("effort"),
          "Feed-forward effort of a joint's actuator, delayed and clipped with its PD effort.")
      .def(
          "reset_actuator_history",
          [](Simulation& s) { locked(s, [&] { s.reset_actuator_history(); }); },
          "Empties every actuator's delay history (the next step sees its own command).")
      .def_property_readonly("actuator_force", &Simulation::actuator_force, ref,
                             "Explicit actuators' effort in the last step (nv,), read-only view.")
      .def_property_readonly("drive_force", &Simulation::drive_force, ref,
                             "Drive force of each dof in the last step (nv,), read-only view.")
      .def_property_readonly("limit_force", &Simulation::limit_force, ref,
                             "Position-limit force of each dof in the last step (nv,), view.")
      .def_property_readonly("friction_force", &Simulation::friction_force, ref,
                             "Joint-friction force of each dof in the last step (nv,), view.")
      .def_property_readonly("velocity_limit_force", &Simulation::velocity_limit_force, ref,
                             "Velocity-limit force of each dof in the last step (nv,), view.")
      .def(
          "step",
          [](Simulation& s, py::handle count) {
            const int n = to_int(count, "step: count", 0);
            step_in_chunks(s, n, [&](int k) { s.step(k); });
          },
          py::arg("count") = 1,
          "Advances count steps of options.dt without the GIL. DivergenceError (a RuntimeError) "
          "if a step would give a non-finite value: the state is that before the step that "
          "diverged, the steps before it are kept. Ctrl-C raises KeyboardInterrupt with the state "
          "of the last whole step (step_count tells how many were made).");

  m.def(
      "set_drive_targets",
      [](Simulation& s, py::handle positions, py::handle velocities) {
        const int nv = model_of(s)->nv;
        const VecX p = to_vector(positions, nv, "positions");
        const VecX v = to_vector(velocities, nv, "velocities");
        locked(s, [&] { set_drive_targets(s, p, v); });
      },
      py::arg("sim"), py::arg("positions"), py::arg("velocities"),
      "The C++ free function; the same as sim.set_drive_targets(positions, velocities).");
  m.def(
      "set_drive_gains",
      [](Simulation& s, py::handle stiffness, py::handle damping, py::handle type) {
        const int nv = model_of(s)->nv;
        const VecX kp = to_vector(stiffness, nv, "stiffness", true);
        const VecX kd = to_vector(damping, nv, "damping", true);
        const DriveType t = to_drive_type(type);
        locked(s, [&] { set_drive_gains(s, kp, kd, t); });
      },
      py::arg("sim"), py::arg("stiffness"), py::arg("damping"), py::arg("type") = DriveType::force,
      "The C++ free function; the same as sim.set_drive_gains(stiffness, damping, type).");

  // ---- batch ----------------------------------------------------------------------------------
  // States are read-only (N, n) views of the batch's arrays (reference_internal keeps the batch
  // alive); setters take env_ids (None: all) and values as a scalar, one row for every
  // environment named, or one row each.
  py::class_<Batch, BatchHolder>(m, "Batch",
                                 "N environments of one robot stepped together on all cores, "
                                 "each bit-identical to stepping it alone, for any num_threads. "
                                 "States are read-only (N, nq) / (N, nv) views of the batch's "
                                 "arrays; sim(i) is environment i, live.")
      .def(py::init([](ModelPtr model, py::handle count, double dt, py::handle solver,
                       py::handle pi, py::handle vi, py::handle compat, py::handle kp,
                       py::handle kd, py::handle type) {
             const int n = to_int(count, "count", 1);
             Simulation prototype(std::move(model), make_options(dt, solver, pi, vi, compat));
             initial_drives(prototype, kp, kd, type);
             return BatchHolder(new Batch(prototype, n));
           }),
           py::arg("model"), py::arg("count"), py::arg("dt") = 1.0 / 60.0,
           py::arg("solver") = "pgs", py::arg("position_iterations") = 4,
           py::arg("velocity_iterations") = 1, py::arg("compat") = "none",
           py::arg("stiffness") = py::none(), py::arg("damping") = py::none(),
           py::arg("drive_type") = "force",
           "count environments, each a new Simulation of model, with the arguments of "
           "Simulation(model, dt, ..., stiffness, damping, drive_type).")
      .def(py::init([](const Simulation& prototype, py::handle count) {
             const int n = to_int(count, "count", 1);
             return locked(prototype, [&] { return BatchHolder(new Batch(prototype, n)); });
           }),
           py::arg("prototype"), py::arg("count"),
           "count copies of prototype: its state, drives, limits and other settings.")
      .def("__len__", &Batch::size, "Number of environments.")  // fixed at construction: no lock
      .def("size", &Batch::size, "Number of environments.")
      .def_property_readonly("model", [](const Batch& b) { return to_python(model_of(b)); },
                             "Environment 0's Model (all share its topology).")
      .def(
          "sim",
          [](Batch& b, py::handle i) -> Simulation& {
            constexpr auto lo = std::numeric_limits<long long>::min();
            constexpr auto hi = std::numeric_limits<long long>::max();
            const long long index = to_int64(i, "environment index", lo, hi);
            Simulation& s = b.sim(index_in(index, b.size(), "environment index"));
            auto lock = lock_for(&b);
            lock_table()[&s] = std::move(lock);  // the environment shares the batch's lock
            return s;
          },
          py::arg("i"), ref,
          "Environment i as a live Simulation (a reference into the batch: its q is row i of "
          "batch.q; it keeps the batch alive and shares its lock).")
      .def_property(
          "num_threads", [](const Batch& b) { return locked(b, [&] { return b.num_threads(); }); },
          [](Batch& b, py::handle threads) {
            const int n = to_int(threads, "num_threads", 0);
            locked(b, [&] { b.set_num_threads(n); });
          },
          "Threads step() uses: 0 = all cores (default), 1 = serial.")
      .def(
          "set_num_threads",
          [](Batch& b, py::handle threads) {
            const int n = to_int(threads, "num_threads", 0);
            locked(b, [&] { b.set_num_threads(n); });
          },
          py::arg("threads"), "Threads step() uses: 0 = all cores, 1 = serial; ValueError if < 0.")
      .def(
          "effective_num_threads",
          [](const Batch& b) { return locked(b, [&] { return b.effective_num_threads(); }); },
          "The threads step() will use.")
      .def(
          "set_options",
          [](Batch& b, const SimulationOptions& o) { locked(b, [&] { b.set_options(o); }); },
          py::arg("options"), "Sets every environment's options.")
      .def_property_readonly("q", &Batch::q, ref, "Configurations (N, nq), a read-only view.")
      .def_property_readonly("qd", &Batch::qd, ref, "Joint velocities (N, nv), a read-only view.")
      .def_property_readonly("applied_force", &Batch::applied_force, ref,
                             "Applied joint forces (N, nv), a read-only view.")
      .def_property_readonly("drive_force", &Batch::drive_force, ref,
                             "Drive forces of the last step (N, nv), a read-only view.")
      .def_property_readonly("limit_force", &Batch::limit_force, ref,
                             "Position-limit forces of the last step (N, nv), a read-only view.")
      .def_property_readonly("friction_force", &Batch::friction_force, ref,
                             "Joint-friction forces of the last step (N, nv), a read-only view.")
      .def_property_readonly("velocity_limit_force", &Batch::velocity_limit_force, ref,
                             "Velocity-limit forces of the last step (N, nv), a read-only view.")
      .def(
          "set_q",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nq, "q");
            locked(b, [&] { b.set_q(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Sets the configurations of env_ids (None: all): a scalar, (nq,) for each or (k, nq); "
          "quaternions are normalised.")
      .def(
          "set_qd",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nv, "qd");
            locked(b, [&] { b.set_qd(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Sets the joint velocities of env_ids (None: all): a scalar, (nv,) or (k, nv).")
      .def(
          "set_applied_force",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nv, "applied_force");
            locked(b, [&] { b.set_applied_force(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Sets the applied joint forces of env_ids (None: all): a scalar, (nv,) or (k, nv).")
      .def(
          "set_drive_targets",
          [](Batch& b, py::handle positions, py::handle velocities, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const int nv = model_of(b)->nv;
            const RowMatrix p = to_rows(positions, ids.size(), nv, "positions");
            const RowMatrix v = to_rows(velocities.is_none() ? py::float_(0.0) : velocities,
                                        ids.size(), nv, "velocities");
            locked(b, [&] { b.set_drive_targets(ids, p, v); });
          },
          py::arg("positions"), py::arg("velocities") = 0.0, py::arg("env_ids") = py::none(),
          "Target positions and velocities of env_ids (None: all), each a scalar, (nv,) or "
          "(k, nv); velocities default to 0. Nothing changes on a ValueError.")
      .def(
          "set_drive_gains",
          [](Batch& b, py::handle stiffness, py::handle damping, py::handle type,
             py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const int nv = model_of(b)->nv;
            const RowMatrix kp = to_rows(stiffness, ids.size(), nv, "stiffness");
            const RowMatrix kd = to_rows(damping, ids.size(), nv, "damping");
            const DriveType t = to_drive_type(type);
            locked(b, [&] { b.set_drive_gains(ids, kp, kd, t); });
          },
          py::arg("stiffness"), py::arg("damping"), py::arg("type") = DriveType::force,
          py::arg("env_ids") = py::none(),
          "Stiffness and damping of env_ids (None: all), each a scalar, (nv,) or (k, nv), as "
          "Simulation.set_drive_gains. Nothing changes on a ValueError.")
      .def(
          "set_drive",
          [](Batch& b, py::handle joint, const Drive& d) {
            const std::string j = to_str(joint, "joint");
            locked(b, [&] { b.set_drive(j, d); });
          },
          py::arg("joint"), py::arg("drive"), "The same Drive on one joint (name) of every copy.")
      .def(
          "set_actuator",
          [](Batch& b, py::handle joint, const ExplicitActuator& a, py::handle env_ids) {
            const NameOrIndex j = joint_arg(joint);
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            locked(b, [&] {
              // A copy with a drive refuses first (set_actuator's message, nothing set yet);
              // then the first copy checks what all share (joint, values).
              const int dof = dof_of(b.model(), j);
              for (int i : ids)
                if (a.kind != ActuatorKind::none && b.sim(i).drive(dof).type != DriveType::none)
                  b.sim(i).set_actuator(dof, a);
              for (int i : ids) b.sim(i).set_actuator(dof, a);
            });
          },
          py::arg("joint"), py::arg("actuator"), py::arg("env_ids") = py::none(),
          "The same ExplicitActuator on one joint (name or dof) of the copies env_ids (all for "
          "None), each with an empty delay history. Nothing changes on a ValueError.")
      .def(
          "reset",
          [](Batch& b, py::handle env_ids, py::handle q, py::handle qd) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const auto model = model_of(b);
            std::optional<RowMatrix> q0, qd0;
            if (!q.is_none()) q0 = to_rows(q, ids.size(), model->nq, "q");
            if (!qd.is_none()) qd0 = to_rows(qd, ids.size(), model->nv, "qd");
            locked(b, [&] { b.reset(ids, q0, qd0); });
          },
          py::arg("env_ids"), py::arg("q") = py::none(), py::arg("qd") = py::none(),
          "Starts env_ids (None: all) again: q (default: the batch's initial configuration), qd "
          "(default 0), applied and output forces 0, clock 0; drives and settings stay; the "
          "other environments are untouched.")
      .def(
          "set_armature",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nv, "armature");
            locked(b, [&] { b.set_armature(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Armature of env_ids (None: all): a scalar, (nv,) or (k, nv); each gets its own model.")
      .def(
          "set_joint_limits",
          [](Batch& b, py::handle lower, py::handle upper, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const int nv = model_of(b)->nv;
            const RowMatrix lo = to_rows(lower, ids.size(), nv, "lower");
            const RowMatrix hi = to_rows(upper, ids.size(), nv, "upper");
            locked(b, [&] { b.set_joint_limits(ids, lo, hi); });
          },
          py::arg("lower"), py::arg("upper"), py::arg("env_ids") = py::none(),
          "Joint limits of env_ids (None: all), each a scalar, (nv,) or (k, nv); dofs of "
          "spherical and floating joints must be given the -inf / inf they have.")
      .def(
          "set_joint_friction",
          [](Batch& b, py::handle static_effort, py::handle dynamic_effort, py::handle viscous,
             py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const int nv = model_of(b)->nv;
            const RowMatrix s = to_rows(static_effort, ids.size(), nv, "static");
            const RowMatrix d = dynamic_effort.is_none()
                                    ? s
                                    : to_rows(dynamic_effort, ids.size(), nv, "dynamic");
            const RowMatrix v = to_rows(viscous, ids.size(), nv, "viscous");
            locked(b, [&] { b.set_joint_friction(ids, s, d, v); });
          },
          py::arg("static"), py::arg("dynamic") = py::none(), py::arg("viscous") = 0.0,
          py::arg("env_ids") = py::none(),
          "Joint friction of env_ids (None: all), each a scalar, (nv,) or (k, nv); dynamic "
          "defaults to static.")
      .def(
          "set_max_joint_velocity",
          [](Batch& b, py::handle values, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix v = to_rows(values, ids.size(), model_of(b)->nv, "max_velocity");
            locked(b, [&] { b.set_max_joint_velocity(ids, v); });
          },
          py::arg("values"), py::arg("env_ids") = py::none(),
          "Largest |qd| of env_ids (None: all): a scalar, (nv,) or (k, nv); inf for none.")
      .def(
          "set_link_mass",
          [](Batch& b, py::handle link, py::handle mass, py::handle env_ids, bool scale) {
            const NameOrIndex l = link_arg(link);
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const bool scalar = as_float_array(mass, "mass").ndim() == 0;
            const VecX m = to_vector(mass, scalar ? 1 : static_cast<Eigen::Index>(ids.size()),
                                     "mass", true);
            locked(b, [&] { b.set_link_mass(ids, link_of(b.model(), l), m, scale); });
          },
          py::arg("link"), py::arg("mass"), py::arg("env_ids") = py::none(),
          py::arg("scale_inertia") = true,
          "Mass of a link (name or index) in env_ids (None: all): a scalar or (k,). "
          "scale_inertia: its inertia scales with the mass (Isaac Lab's mass randomisation).")
      .def(
          "set_link_com",
          [](Batch& b, py::handle link, py::handle com, py::handle env_ids) {
            const NameOrIndex l = link_arg(link);
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix c = to_rows(com, ids.size(), 3, "com", /*scalar_ok=*/false);
            locked(b, [&] { b.set_link_com(ids, link_of(b.model(), l), c); });
          },
          py::arg("link"), py::arg("com"), py::arg("env_ids") = py::none(),
          "Centre of mass (link frame) of a link in env_ids (None: all): (3,) or (k, 3).")
      .def(
          "armature", [](const Batch& b) { return locked(b, [&] { return b.armature(); }); },
          "Every environment's armature (N, nv), a copy.")
      .def(
          "joint_limits",
          [](const Batch& b) {
            return locked(b, [&] { return py::make_tuple(b.lower_limit(), b.upper_limit()); });
          },
          "(lower, upper), (N, nv) each, copies.")
      .def(
          "joint_friction",
          [](const Batch& b) {
            return locked(b, [&] {
              return py::make_tuple(b.static_friction(), b.dynamic_friction(),
                                    b.viscous_friction());
            });
          },
          "(static, dynamic, viscous), (N, nv) each, copies.")
      .def(
          "max_joint_velocity",
          [](const Batch& b) { return locked(b, [&] { return b.max_joint_velocity(); }); },
          "(N, nv), a copy.")
      .def(
          "link_mass",
          [](const Batch& b, py::handle link) {
            const NameOrIndex l = link_arg(link);
            return locked(b, [&] { return b.link_mass(link_of(b.model(), l)); });
          },
          py::arg("link"), "A link's mass in every environment (N,), a copy.")
      .def(
          "link_com",
          [](const Batch& b, py::handle link) {
            const NameOrIndex l = link_arg(link);
            return locked(b, [&] { return b.link_com(link_of(b.model(), l)); });
          },
          py::arg("link"), "A link's centre of mass in every environment (N, 3), a copy.")
      .def(
          "observe",
          [](const Batch& b, py::handle fields) {
            const std::vector<Observation> f = to_observations(fields);
            return locked(b, [&] { return b.observe(f); });
          },
          py::arg("fields"),
          "The fields (names from q, qd, applied_force, drive_force, limit_force, "
          "friction_force, velocity_limit_force, target_position, target_velocity) side by "
          "side in one new (N, k) array.")
      .def(
          "frame_positions",
          [](const Batch& b, py::handle link, py::handle point) {
            const NameOrIndex l = link_arg(link);
            const Vec3 p = point.is_none() ? Vec3::Zero() : to_vec3(point, "point");
            return locked(b, [&] { return b.frame_positions(link_of(b.model(), l), p); });
          },
          py::arg("link"), py::arg("point") = py::none(),
          "World position of a point (link coordinates, default its origin) on a link (name or "
          "index) in every environment, (N, 3), a new array.")
      .def(
          "step",
          [](Batch& b, py::handle count) {
            const int n = to_int(count, "step: count", 0);
            // A copy that diverged stays at its step and diverges again in every later chunk
            // (same state, same inputs), so the last chunk's error names every diverged copy, as
            // one Batch::step(n) would.
            std::exception_ptr diverged;
            step_in_chunks(b, n, [&](int k) {
              try {
                b.step(k);
              } catch (const DivergenceError&) {
                diverged = std::current_exception();
              }
            });
            if (diverged) std::rethrow_exception(diverged);
          },
          py::arg("count") = 1,
          "Steps every copy count times, in parallel, without the GIL. A copy that diverges "
          "stops at that step with its state from before it; the others make all their steps; "
          "then DivergenceError names the lowest diverged copy (sim(i).step_count tells how far "
          "each got). Ctrl-C raises KeyboardInterrupt with every copy at a whole step.");

  // ---- control steps (sim/control_step.hpp): Simulation.step_control, Batch.step_control ------
  {
    auto control_of = [](py::handle substeps, py::handle targets) {
      ControlStep c;
      c.substeps = to_int(substeps, "step_control: substeps", 1, kMaxSubsteps);
      const std::string t = to_str(targets, "step_control: targets");
      if (t != "hold" && t != "linear")
        throw std::invalid_argument("step_control: targets = '" + t +
                                    "': must be 'hold' or 'linear'");
      c.targets = t == "linear" ? TargetInterpolation::linear : TargetInterpolation::hold;
      return c;
    };
    // A scalar for every copy and dof, (nv,) for every copy, or (N, nv).
    auto batch_targets = [](py::handle obj, const Batch& b, const std::string& what) {
      const int n = b.size();
      const RowMatrix rows = to_rows(obj, static_cast<size_t>(n), model_of(b)->nv, what);
      return rows.rows() == n ? rows : RowMatrix(rows.replicate(n, 1));
    };
    py::object sim_class = m.attr("Simulation"), batch_class = m.attr("Batch");
    sim_class.attr("step_control") = py::cpp_function(
        [control_of](Simulation& s, py::handle position, py::handle velocity,
                     py::handle substeps, py::handle targets) {
          const int nv = model_of(s)->nv;
          const VecX p = to_vector(position, nv, "step_control: target_position", true);
          const VecX v = to_vector(velocity, nv, "step_control: target_velocity", true);
          const ControlStep c = control_of(substeps, targets);
          step_in_chunks(s, 1, [&](int) { step_control(s, p, v, c); });
        },
        py::name("step_control"), py::is_method(sim_class), py::arg("target_position"),
        py::arg("target_velocity") = 0.0, py::arg("substeps") = 1, py::arg("targets") = "hold",
        "One control step: substeps physics steps of options.dt with the drive targets (nv,) or a "
        "scalar, held ('hold') or interpolated from the previous ones ('linear'; "
        "docs/math/control_step.md), without the GIL. DivergenceError names the sub-step.");
    batch_class.attr("step_control") = py::cpp_function(
        [control_of, batch_targets](Batch& b, py::handle position, py::handle velocity,
                                    py::handle substeps, py::handle targets) {
          const RowMatrix p = batch_targets(position, b, "step_control: target_position");
          const RowMatrix v = batch_targets(velocity, b, "step_control: target_velocity");
          const ControlStep c = control_of(substeps, targets);
          step_in_chunks(b, 1, [&](int) { step_control(b, p, v, c); });
        },
        py::name("step_control"), py::is_method(batch_class), py::arg("target_position"),
        py::arg("target_velocity") = 0.0, py::arg("substeps") = 1, py::arg("targets") = "hold",
        "Simulation.step_control for every copy: targets (N, nv), (nv,) for all or a scalar; "
        "divergence as Batch.step, per sub-step.");
  }

  // ---- io -------------------------------------------------------------------------------------
  py::enum_<UrdfEffort>(m, "UrdfEffort", "What a URDF <limit effort> becomes.")
      .value("none", UrdfEffort::none, "informative only")
      .value("max_force", UrdfEffort::max_force, "every implicit drive's max_force")
      .value("effort_limit", UrdfEffort::effort_limit, "every explicit actuator's effort_limit");
  py::class_<UrdfOptions>(m, "UrdfOptions", "How to import a URDF.")
      .def(py::init([](bool fixed_base, py::handle gravity, py::handle effort) {
             UrdfOptions o;
             o.fixed_base = fixed_base;
             o.gravity = to_vec3(gravity, "gravity");
             o.effort = to_urdf_effort(effort);
             return o;
           }),
           py::arg("fixed_base") = true, py::arg("gravity") = py::make_tuple(0.0, 0.0, -9.81),
           py::arg("effort") = UrdfEffort::none,
           "fixed_base False gives the root a floating joint; effort: what <limit effort> "
           "becomes, 'none' | 'max_force' | 'effort_limit' (apply_urdf_effort_limits).")
      .def_property(
          "effort", [](const UrdfOptions& o) { return o.effort; },
          [](UrdfOptions& o, py::handle e) { o.effort = to_urdf_effort(e); },
          "UrdfEffort: none, max_force (drives) or effort_limit (explicit actuators)")
      .def_readwrite("fixed_base", &UrdfOptions::fixed_base, "root welded to the world")
      .def_property(
          "gravity", [](const UrdfOptions& o) { return o.gravity; },
          [](UrdfOptions& o, py::handle g) { o.gravity = to_vec3(g, "gravity"); }, "gravity (3,)");

  py::class_<UrdfMimic>(m, "UrdfMimic", "A <mimic> tag (read, not simulated).")
      .def_readonly("joint", &UrdfMimic::joint, "the mimicking joint")
      .def_readonly("leader", &UrdfMimic::leader, "the joint it follows")
      .def_readonly("multiplier", &UrdfMimic::multiplier, "joint = multiplier * leader + offset")
      .def_readonly("offset", &UrdfMimic::offset, "joint = multiplier * leader + offset");

  py::class_<UrdfRobot>(m, "UrdfRobot", "A robot read from URDF and its Model.")
      .def_readonly("path", &UrdfRobot::path, "the file")
      .def_readonly("name", &UrdfRobot::name, "<robot name>")
      .def_readonly("root_link", &UrdfRobot::root_link, "root link name")
      .def_readonly("root_joint", &UrdfRobot::root_joint, "name of the root's joint")
      .def_property_readonly("options", [](const UrdfRobot& r) { return r.options; },
                             "the UrdfOptions (a copy)")
      .def_readwrite("links", &UrdfRobot::links,
                     "the LinkSpecs after merging (a copy; assign an edited list and call "
                     "rebuild())")
      .def_property_readonly("model", [](const UrdfRobot& r) { return to_python(r.model); },
                             "The Model.")
      .def_readonly("joint_order", &UrdfRobot::joint_order, "every <joint> in document order")
      .def_readonly("dof_order", &UrdfRobot::dof_order, "model dofs in URDF document order")
      .def_readonly("mimics", &UrdfRobot::mimics, "list of UrdfMimic")
      .def_readonly("warnings", &UrdfRobot::warnings, "messages for the user")
      .def_readonly("effort_limits", &UrdfRobot::effort_limits, "URDF effort limit per joint")
      .def("rebuild", &UrdfRobot::rebuild, "Builds model from links again.");

  m.def(
      "apply_urdf_effort_limits",
      [](const UrdfRobot& robot, Simulation& sim) {
        locked(sim, [&] { apply_urdf_effort_limits(robot, sim); });
      },
      py::arg("robot"), py::arg("sim"),
      "Gives the URDF effort limits to sim's drives (max_force) or explicit actuators "
      "(effort_limit) that have none, as robot.options.effort says.");
  m.def("load_urdf", &load_urdf, py::arg("path"), py::arg("options") = UrdfOptions{},
        "Reads a URDF file; InputError (a ValueError) naming the file, element and value.");
  m.def("parse_urdf", &parse_urdf, py::arg("xml"), py::arg("name"),
        py::arg("options") = UrdfOptions{},
        "Reads URDF text; name stands for the file in messages.");

  py::class_<SineTarget>(m, "SineTarget", "offset + amplitude sin(2 pi frequency t + phase).")
      .def_readonly("amplitude", &SineTarget::amplitude, "amplitude")
      .def_readonly("frequency", &SineTarget::frequency, "Hz")
      .def_readonly("phase", &SineTarget::phase, "rad")
      .def_readonly("offset", &SineTarget::offset, "offset")
      .def("position", &SineTarget::position, py::arg("t"), "Target position at t.")
      .def("velocity", &SineTarget::velocity, py::arg("t"), "Target velocity at t.");

  py::class_<DriveSpec>(m, "DriveSpec", "A scene's drive on one joint.")
      .def_readonly("joint", &DriveSpec::joint, "joint name")
      .def_readonly("dof", &DriveSpec::dof, "dof index")
      .def_readonly("drive", &DriveSpec::drive, "the Drive")
      .def_readonly("sine", &DriveSpec::sine, "SineTarget or None")
      .def_readonly("actuator", &DriveSpec::actuator, "ExplicitActuator or None")
      .def("target_at", &DriveSpec::target_at, py::arg("t"), "(position, velocity) at t.");

  py::class_<Scene>(m, "Scene", "A scene file: robot, options, initial state and drives.")
      .def_readonly("path", &Scene::path, "the scene file")
      .def_readonly("model_path", &Scene::model_path, "the URDF")
      // Copies: a reference would let Python edit the scene's robot and options in place.
      .def_property_readonly("robot", [](const Scene& s) { return s.robot; },
                             "the UrdfRobot (a copy)")
      .def_property_readonly("options", [](const Scene& s) { return s.options; },
                             "the SimulationOptions (a copy)")
      .def_readonly("steps", &Scene::steps, "number of steps")
      .def_readonly("q0", &Scene::q0, "initial q (nq,)")
      .def_readonly("qd0", &Scene::qd0, "initial qd (nv,)")
      .def_readonly("drives", &Scene::drives, "list of DriveSpec in URDF joint order")
      .def_property_readonly("model", [](const Scene& s) { return to_python(s.model()); },
                             "The Model.");

  m.def("load_scene", &load_scene, py::arg("path"),
        "Reads a scene file (YAML or JSON); InputError (a ValueError) naming the file, key and "
        "value.");
  m.def("parse_scene", &parse_scene, py::arg("text"), py::arg("path"),
        "Reads scene text; path names the file and anchors the model path.");
  m.def("make_simulation", &make_simulation, py::arg("scene"),
        "A Simulation in the scene's initial state with its drives and joint settings.");
  m.def(
      "apply_targets",
      [](const Scene& scene, Simulation& sim, py::handle step_index) {
        // k + 1 must fit the C++ int.
        const int k = to_int(step_index, "apply_targets: step_index", 0, kIntMax - 1);
        locked(sim, [&] { apply_targets(scene, sim, k); });
      },
      py::arg("scene"), py::arg("sim"), py::arg("step_index"),
      "Sets the sine targets for step k (0-based, at most 2**31 - 2): those at t = (k + 1) dt.");

  py::register_exception<CheckpointError>(m, "CheckpointError", PyExc_ValueError).doc() =
      "A file that is not a checkpoint of this model (truncated, corrupt, other version or "
      "model); a ValueError.";
  m.def(
      "save_checkpoint",
      [](const Simulation& sim, const std::filesystem::path& path) {
        locked_nogil(sim, [&] { save_checkpoint(sim, path); });
      },
      py::arg("sim"), py::arg("path"),
      "Writes the full simulation state (state, clock, inputs, settings, last forces) "
      "atomically, bit-exact.");
  m.def(
      "load_checkpoint",
      [](const std::filesystem::path& path, Simulation& sim) {
        locked_nogil(sim, [&] { load_checkpoint(path, sim); });
      },
      py::arg("path"), py::arg("sim"),
      "Restores a checkpoint into sim (same model) in place: views of sim stay valid and show "
      "the restored state. CheckpointError and sim unchanged otherwise.");

  bind_dynamics(m);
  bind_names(m);
  bind_fit(m);  // python/bind_fit.cpp
}
