// SimdBatch: N environments of one fixed-base robot stepped W at a time in SIMD lanes
// (docs/simd_batch.md).
#include "bindings.hpp"

#include "featherdrive/sim/simd_batch.hpp"

namespace py = pybind11;
using namespace featherdrive;
using namespace featherdrive::python;

namespace {

struct SimdBatchDeleter {
  void operator()(SimdBatch* batch) const {
    lock_table().erase(batch);
    delete batch;
  }
};
using SimdBatchHolder = std::unique_ptr<SimdBatch, SimdBatchDeleter>;

std::optional<SimdIsa> to_isa(py::handle obj) {
  if (obj.is_none()) return std::nullopt;
  const std::string name = to_str(obj, "isa");
  for (SimdIsa isa : {SimdIsa::sse2, SimdIsa::avx2, SimdIsa::avx512})
    if (name == to_string(isa)) return isa;
  throw std::invalid_argument("isa = '" + name + "': expected 'sse2', 'avx2' or 'avx512'");
}

// A per-dof setter of env_ids (None: all) taking (N, nv)-shaped values.
template <class Set>
void dof_rows(SimdBatch& b, py::handle env_ids,
              std::initializer_list<std::pair<py::handle, const char*>> values, Set set) {
  const std::vector<int> ids = to_env_ids(env_ids, b.size());
  std::vector<RowMatrix> rows;
  for (const auto& [v, what] : values) rows.push_back(to_rows(v, ids.size(), b.model().nv, what));
  locked(b, [&] { set(ids, rows); });
}

}  // namespace

void featherdrive::python::bind_simd(py::module_& m) {
  m.def(
      "available_simd_isas",
      [] {
        std::vector<std::string> out;
        for (SimdIsa isa : available_simd_isas()) out.push_back(to_string(isa));
        return out;
      },
      "The instruction sets SimdBatch can use on this CPU, narrowest first.");
  py::class_<SimdBatch, SimdBatchHolder>(
      m, "SimdBatch",
      "N environments of one fixed-base robot (revolute, prismatic and fixed joints) stepped W "
      "at a time in SIMD lanes (W = 2, 4, 8 for sse2, avx2, avx512, the widest the CPU has or "
      "FEATHERDRIVE_SIMD), blocks on num_threads threads; bits independent of lane, batch size, "
      "width and threads. States are read-only (N, nq) / (N, nv) views (docs/simd_batch.md).")
      .def(py::init([](const Simulation& prototype, py::handle count, py::handle isa) {
             const int n = to_int(count, "count", 1, Batch::kMaxSize);
             const std::optional<SimdIsa> i = to_isa(isa);
             return locked(prototype,
                           [&] { return SimdBatchHolder(new SimdBatch(prototype, n, i)); });
           }),
           py::arg("prototype"), py::arg("count"), py::arg("isa") = py::none(),
           "count copies of prototype (state, drives, limits, options); ValueError naming the "
           "setting and joint for what the SIMD step does not simulate.")
      .def("__len__", &SimdBatch::size)
      .def_property_readonly("isa", [](const SimdBatch& b) { return to_string(b.isa()); })
      .def_property_readonly("width", &SimdBatch::width)
      .def_property_readonly("model", [](const SimdBatch& b) { return to_python(model_of(b)); })
      .def_property(
          "num_threads", [](const SimdBatch& b) { return b.num_threads(); },
          [](SimdBatch& b, py::handle threads) {
            const int n = to_int(threads, "num_threads", 0);
            locked(b, [&] { b.set_num_threads(n); });
          },
          "Threads step() uses: 0 = all cores (default), 1 = serial.")
      .def_property_readonly("q", &SimdBatch::q, ref, "Configurations (N, nq), read-only view.")
      .def_property_readonly("qd", &SimdBatch::qd, ref, "Joint velocities (N, nv), read-only.")
      .def_property_readonly("applied_force", &SimdBatch::applied_force, ref)
      .def_property_readonly("drive_force", &SimdBatch::drive_force, ref)
      .def_property_readonly("limit_force", &SimdBatch::limit_force, ref)
      .def_property_readonly("friction_force", &SimdBatch::friction_force, ref)
      .def_property_readonly("velocity_limit_force", &SimdBatch::velocity_limit_force, ref)
      .def_property_readonly("step_count", [](const SimdBatch& b) { return b.step_count(); })
      .def(
          "set_q",
          [](SimdBatch& b, py::handle v, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const RowMatrix q = to_rows(v, ids.size(), b.model().nq, "q");
            locked(b, [&] { b.set_q(ids, q); });
          },
          py::arg("values"), py::arg("env_ids") = py::none())
      .def(
          "set_qd",
          [](SimdBatch& b, py::handle v, py::handle env_ids) {
            dof_rows(b, env_ids, {{v, "qd"}}, [&](auto& ids, auto& r) { b.set_qd(ids, r[0]); });
          },
          py::arg("values"), py::arg("env_ids") = py::none())
      .def(
          "set_applied_force",
          [](SimdBatch& b, py::handle v, py::handle env_ids) {
            dof_rows(b, env_ids, {{v, "applied_force"}},
                     [&](auto& ids, auto& r) { b.set_applied_force(ids, r[0]); });
          },
          py::arg("values"), py::arg("env_ids") = py::none())
      .def(
          "set_drive_targets",
          [](SimdBatch& b, py::handle p, py::handle v, py::handle env_ids) {
            dof_rows(b, env_ids, {{p, "positions"}, {v, "velocities"}},
                     [&](auto& ids, auto& r) { b.set_drive_targets(ids, r[0], r[1]); });
          },
          py::arg("positions"), py::arg("velocities") = 0.0, py::arg("env_ids") = py::none())
      .def(
          "set_drive_gains",
          [](SimdBatch& b, py::handle kp, py::handle kd, py::handle type, py::handle env_ids) {
            const DriveType t = to_drive_type(type);
            dof_rows(b, env_ids, {{kp, "stiffness"}, {kd, "damping"}},
                     [&](auto& ids, auto& r) { b.set_drive_gains(ids, r[0], r[1], t); });
          },
          py::arg("stiffness"), py::arg("damping"), py::arg("type") = "force",
          py::arg("env_ids") = py::none())
      .def(
          "set_joint_limits",
          [](SimdBatch& b, py::handle lo, py::handle hi, py::handle env_ids) {
            dof_rows(b, env_ids, {{lo, "lower"}, {hi, "upper"}},
                     [&](auto& ids, auto& r) { b.set_joint_limits(ids, r[0], r[1]); });
          },
          py::arg("lower"), py::arg("upper"), py::arg("env_ids") = py::none())
      .def(
          "set_joint_friction",
          [](SimdBatch& b, py::handle st, py::handle dy, py::handle vi, py::handle env_ids) {
            dof_rows(b, env_ids,
                     {{st, "static"}, {dy.is_none() ? st : dy, "dynamic"}, {vi, "viscous"}},
                     [&](auto& ids, auto& r) { b.set_joint_friction(ids, r[0], r[1], r[2]); });
          },
          py::arg("static"), py::arg("dynamic") = py::none(), py::arg("viscous") = 0.0,
          py::arg("env_ids") = py::none(), "As Batch.set_joint_friction.")
      .def(
          "set_armature",
          [](SimdBatch& b, py::handle v, py::handle env_ids) {
            dof_rows(b, env_ids, {{v, "armature"}},
                     [&](auto& ids, auto& r) { b.set_armature(ids, r[0]); });
          },
          py::arg("values"), py::arg("env_ids") = py::none())
      .def(
          "set_link_mass",
          &set_link_mass_of<SimdBatch>,
          py::arg("link"), py::arg("mass"), py::arg("env_ids") = py::none(),
          py::arg("scale_inertia") = true, "As Batch.set_link_mass.")
      .def(
          "set_link_com",
          [](SimdBatch& b, py::handle link, py::handle com, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            const NameOrIndex l = link_arg(link);
            const RowMatrix c = to_rows(com, ids.size(), 3, "com");
            locked(b, [&] { b.set_link_com(ids, link_of(b.model(), l), c); });
          },
          py::arg("link"), py::arg("com"), py::arg("env_ids") = py::none())
      .def(
          "reset",
          [](SimdBatch& b, py::handle env_ids) {
            const std::vector<int> ids = to_env_ids(env_ids, b.size());
            locked(b, [&] { b.reset(ids); });
          },
          py::arg("env_ids") = py::none(), "Starts env_ids again from initial q, qd = 0.")
      .def_property_readonly("stiffness", &SimdBatch::stiffness)
      .def_property_readonly("damping", &SimdBatch::damping)
      .def_property_readonly("lower_limit", &SimdBatch::lower_limit)
      .def_property_readonly("upper_limit", &SimdBatch::upper_limit)
      .def_property_readonly("armature", &SimdBatch::armature)
      .def(
          "divergences",
          [](const SimdBatch& b) {
            py::dict out;
            for (int e = 0; e < b.size(); ++e)
              if (const auto& d = b.divergences()[static_cast<size_t>(e)])
                out[py::int_(e)] = d->message;
            return out;
          },
          "{environment: message} of the environments that stopped.")
      .def(
          "simulation",
          [](const SimdBatch& b, py::handle i) {
            constexpr auto lo = std::numeric_limits<long long>::min();
            constexpr auto hi = std::numeric_limits<long long>::max();
            const int index =
                index_in(to_int64(i, "environment index", lo, hi), b.size(), "environment index");
            return locked(b, [&] { return SimulationHolder(new Simulation(b.simulation(index))); });
          },
          py::arg("i"), "Environment i as a Simulation of its own (a copy).")
      .def(
          "step",
          [](SimdBatch& b, py::handle count) {
            const int n = to_int(count, "step: count", 0);
            // A stopped environment stays stopped (it does not diverge again in a later chunk):
            // the first chunk's error is the one to report; divergences() lists them all.
            std::optional<DivergenceError> first;
            step_in_chunks(b, n, [&](int k) {
              try {
                b.step(k);
              } catch (const DivergenceError& e) {
                if (!first) first.emplace(e);
              }
            });
            if (first) throw *first;
          },
          py::arg("count") = 1,
          "Steps every environment count times without the GIL; one that diverges stops with "
          "its state from before that step, the others make all their steps, then "
          "DivergenceError names the lowest one stopped first (divergences(): all of them).");
}
