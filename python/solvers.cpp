// The `sextant` module's `sextant optimize` and `sextant eval`: the CLI's functions (cli/graph_optimization.hpp,
// cli/trajectory_evaluation.hpp), their summaries as dicts with the CLI's JSON keys.
#include "python/module_parts.hpp"

#include "cli/graph_optimization.hpp"
#include "cli/trajectory_evaluation.hpp"

#include <pybind11/stl.h>

#include <algorithm>
#include <cstdio>
#include <optional>
#include <sstream>

namespace sextant::python {
namespace {

py::object summary_value(const tools::SummaryValue& v) {
  return std::visit([](const auto& x) -> py::object { return py::cast(x); }, v);
}

py::dict summary_dict(const tools::Summary& s) {
  py::dict d;
  for (const auto& [k, v] : s.entries()) d[py::str(k)] = summary_value(v);
  return d;
}

bool is_path(const py::handle& obj) {
  return py::isinstance<py::str>(obj) || py::isinstance(obj, py::module_::import("os").attr("PathLike"));
}

// An in-memory graph: records that are g2o lines as sequences, ("VERTEX_SE2", 0, 0.0, 0.0, 0.0),
// ("EDGE_SE2", 0, 1, dx, dy, dtheta, I11, I12, ...), ("FIX", 0); parsed by the g2o reader itself, so the
// checks and messages are the file's, with "graph[K]" naming record K.
graph::G2oGraph graph_from_records(const py::handle& records, const graph::G2oReadOptions& read) {
  std::ostringstream text;
  size_t k = 0;
  for (const py::handle rec : records) {
    if (!py::isinstance<py::sequence>(rec) || py::isinstance<py::str>(rec))
      throw py::value_error("graph[" + std::to_string(k) +
                            "]: expected a sequence like ('VERTEX_SE2', id, x, y, theta)");
    bool first = true;
    for (const py::handle v : rec) {
      if (first) {
        if (!py::isinstance<py::str>(v))
          throw py::value_error("graph[" + std::to_string(k) + "]: the first item must be the g2o tag");
        text << py::cast<std::string>(v);
        first = false;
      } else if (py::isinstance<py::int_>(v) && !py::isinstance<py::bool_>(v)) {
        text << ' ' << py::cast<long long>(v);
      } else if (py::isinstance<py::float_>(v)) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.17g", py::cast<double>(v));
        text << ' ' << buf;
      } else {
        throw py::value_error("graph[" + std::to_string(k) + "]: expected numbers after the tag, got " + type_name(v));
      }
    }
    if (first) throw py::value_error("graph[" + std::to_string(k) + "]: empty record");
    text << '\n';
    ++k;
  }
  std::istringstream in(text.str());
  try {
    return graph::read_g2o(in, "graph", read);
  } catch (const std::runtime_error& e) {
    // "graph:LINE: message" -> "graph[LINE-1]: message"
    std::string msg = e.what();
    const size_t colon = msg.find(':', 6);
    if (msg.rfind("graph:", 0) == 0 && colon != std::string::npos) {
      try {
        msg = "graph[" + std::to_string(std::stol(msg.substr(6, colon - 6)) - 1) + "]" + msg.substr(colon);
      } catch (const std::exception&) {}
    }
    throw py::value_error(msg);
  }
}

// Values in g2o's vertex order: SE2 [x, y, theta], SE3 [x, y, z, qx, qy, qz, qw], points [x, y] / [x, y, z].
py::list variable_values(const graph::Variable& v) {
  py::list l;
  switch (v.kind) {
    case graph::VariableKind::kPose2:
      for (double x : {v.pose2.translation().x(), v.pose2.translation().y(), v.pose2.rotation().angle()}) l.append(x);
      break;
    case graph::VariableKind::kPose3: {
      const auto& t = v.pose3.translation();
      const auto& q = v.pose3.rotation().quaternion();
      for (double x : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}) l.append(x);
      break;
    }
    case graph::VariableKind::kPoint2:
      for (double x : {v.point.x(), v.point.y()}) l.append(x);
      break;
    case graph::VariableKind::kPoint3:
    case graph::VariableKind::kVector3:
      for (double x : {v.point.x(), v.point.y(), v.point.z()}) l.append(x);
      break;
  }
  return l;
}

py::dict optimize(const py::object& graph_or_path, const std::optional<std::string>& output,
                  const tools::GraphOptimizationOptions& options, const std::string& information) {
  graph::G2oReadOptions read;
  try {
    read.information = graph::information_policy_from_name(information);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(e.what());
  }
  graph::G2oGraph g = is_path(graph_or_path) ? graph::read_g2o(py::cast<std::string>(py::str(graph_or_path)), read)
                                             : graph_from_records(graph_or_path, read);
  tools::GraphOptimizationResult r;
  {
    py::gil_scoped_release release;
    r = tools::optimize_graph(g, options, output.value_or(""));
  }
  py::dict poses;
  for (const auto& v : r.variables) poses[py::int_(v.id)] = variable_values(v);
  py::dict out;
  out["summary"] = summary_dict(r.summary);
  out["poses"] = poses;
  out["ok"] = r.ok;
  out["message"] = r.message;
  return out;
}

// A trajectory: a TUM or KITTI file's path (`format`), or rows [t, x, y, z, qx, qy, qz, qw] (seconds, metres, TUM's
// quaternion order).
std::vector<tools::StampedPose> trajectory(const py::object& obj, const char* what, const std::string& format) {
  if (is_path(obj)) {
    const std::string path = py::cast<std::string>(py::str(obj));
    return format == "kitti" ? tools::read_kitti(path) : tools::read_tum(path);
  }
  std::vector<tools::StampedPose> poses;
  size_t k = 0;
  for (const py::handle row : obj) {
    const std::string where = std::string(what) + "[" + std::to_string(k++) + "]";
    const py::list l = as_list(row, where, 8);
    double v[8];
    for (size_t i = 0; i < 8; ++i) v[i] = read_number(l[i], where + "[" + std::to_string(i) + "]");
    tools::StampedPose p;
    p.t = v[0];
    p.pose.position = {v[1], v[2], v[3]};
    p.pose.orientation = Eigen::Quaterniond(v[7], v[4], v[5], v[6]);  // as read_tum: used as given
    poses.push_back(p);
  }
  // As read_tum: sorted by time, a repeated stamp replaces the earlier row.
  std::stable_sort(poses.begin(), poses.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  std::vector<tools::StampedPose> unique;
  for (const auto& p : poses) {
    if (!unique.empty() && unique.back().t == p.t)
      unique.back() = p;
    else
      unique.push_back(p);
  }
  return unique;
}

py::dict evaluate(const py::object& gt, const py::object& est, bool scale, double delta, const std::string& delta_unit,
                  double max_difference, const std::string& format) {
  if (delta_unit != "s" && delta_unit != "f") throw py::value_error("delta_unit: 's' (seconds) or 'f' (frames)");
  if (format != "tum" && format != "kitti") throw py::value_error("format: 'tum' or 'kitti'");
  if (!(delta > 0) || !(max_difference > 0)) throw py::value_error("delta and max_difference must be > 0");
  const tools::EvaluationOptions o{
      scale, delta, delta_unit == "f" ? tools::DeltaUnit::kFrames : tools::DeltaUnit::kSeconds, max_difference};
  const auto g = trajectory(gt, "gt", format), e = trajectory(est, "est", format);
  return summary_dict(tools::evaluate_trajectory(g, e, o).summary(o));
}

}  // namespace

void register_solvers(py::module_& m) {
  m.def(
      "optimize",
      [](const py::object& graph, const std::optional<std::string>& output, const std::string& solver,
         const std::string& init, const std::string& robust, double kernel_width, int max_iters, double tolerance,
         const std::string& ordering, bool incremental, double relin_translation, double relin_rotation, int relin_skip,
         int relin_heavy_every, const std::string& information) {
        tools::GraphOptimizationOptions o;
        try {
          o.solver = tools::solver_from_name(solver), o.init = tools::initial_estimate_from_name(init);
          o.robust = graph::robust_kernel_from_name(robust), o.ordering = tools::ordering_from_name(ordering);
        } catch (const std::invalid_argument& e) {
          throw py::value_error(e.what());
        }
        o.kernel_width = kernel_width, o.max_iters = max_iters, o.tolerance = tolerance, o.incremental = incremental;
        o.relin_translation = relin_translation, o.relin_rotation = relin_rotation, o.relin_skip = relin_skip;
        o.relin_heavy_every = relin_heavy_every;
        return optimize(graph, output, o, information);
      },
      py::arg("graph"), py::arg("output") = py::none(), py::arg("solver") = "gn", py::arg("init") = "auto",
      py::arg("robust") = "none", py::arg("kernel_width") = 1.0, py::arg("max_iters") = 100,
      py::arg("tolerance") = 1e-6, py::arg("ordering") = "block-amd", py::arg("incremental") = false,
      py::arg("relin_translation") = 0.1, py::arg("relin_rotation") = 0.1, py::arg("relin_skip") = 1,
      py::arg("relin_heavy_every") = graph::IncrementalOptions{}.heavy_relinearize_every,
      py::arg("information") = "reject",
      "`sextant optimize`: graph is a g2o file's path or a list of g2o records such as ('VERTEX_SE2', 0, x, y, "
      "theta), ('EDGE_SE2', 0, 1, dx, dy, dtheta, *information_upper_triangle), ('FIX', 0).  Returns {'summary': "
      "the keys of `sextant optimize --json`, 'poses': {id: values in g2o's vertex order}, 'ok', 'message'}; "
      "output= also writes the optimized graph as g2o; information= 'reject' (the default), 'repair' or 'diagonal' "
      "as `sextant optimize --information`.");
  m.def("eval", &evaluate, py::arg("gt"), py::arg("est"), py::arg("scale") = false, py::arg("delta") = 1.0,
        py::arg("delta_unit") = "s", py::arg("max_difference") = 0.02, py::arg("format") = "tum",
        "`sextant eval`: ATE and RPE (TUM benchmark semantics) and the KITTI odometry error of est against gt, each "
        "a file's path (format 'tum' or 'kitti': frame i with frame i) or rows [t, x, y, z, qx, qy, qz, qw].  Returns "
        "the keys of `sextant eval --json`.");
}

}  // namespace sextant::python
