#include "convert/g2o_converter.hpp"

#include "daemon/runtime/codec.hpp"
#include "daemon/runtime/lcm_log.hpp"
#include "estimators/graph/g2o_io.hpp"
#include "estimators/lie/planar_axes.hpp"
#include "eval/trajectory_io.hpp"

#include <algorithm>
#include <map>

namespace sextant::tools {

Eigen::Matrix<double, 6, 6> g2o_information_to_sextant(const Eigen::MatrixXd& info, bool planar) {
  if (planar) return embed_planar(info.topLeftCorner<3, 3>());
  Eigen::Matrix<double, 6, 6> T = Eigen::Matrix<double, 6, 6>::Identity();
  T.bottomRightCorner<3, 3>() *= 0.5;  // e_g2o = T e_sextant to first order
  return T.transpose() * info * T;
}

G2oConversion convert_g2o(const std::string& g2o_path, const std::string& out_lcm, const std::string& gt_tum,
                          const G2oConversionOptions& o) {
  const auto file = graph::read_g2o(g2o_path);
  const auto& vars = file.graph.variables();
  const bool planar = file.dimension == 2;
  // Vertex times by id order.
  std::vector<int> order;
  for (size_t i = 0; i < vars.size(); ++i)
    if (vars[i].is_pose()) order.push_back(static_cast<int>(i));
  std::sort(order.begin(), order.end(), [&](int a, int b) { return vars[static_cast<size_t>(a)].id < vars[static_cast<size_t>(b)].id; });
  std::map<int, int64_t> utime;
  std::map<int64_t, int> by_id;
  for (size_t k = 0; k < order.size(); ++k) {
    utime[order[k]] = o.start_utime + static_cast<int64_t>(k) * o.period_us;
    by_id[vars[static_cast<size_t>(order[k])].id] = order[k];
  }
  // The odometry chain: for each vertex, the first edge (in file order) to the next id.
  std::map<int, const graph::RelativePoseFactor*> chain;  // from vertex index -> edge
  std::vector<const graph::RelativePoseFactor*> loops;
  G2oConversion result;
  for (const auto& f : file.graph.factors()) {
    const auto* rp = dynamic_cast<const graph::RelativePoseFactor*>(f.get());
    if (rp == nullptr) {
      ++result.skipped_edges;
      continue;
    }
    const int a = rp->variables()[0], b = rp->variables()[1];
    const int64_t ia = vars[static_cast<size_t>(a)].id, ib = vars[static_cast<size_t>(b)].id;
    const bool consecutive = std::abs(ia - ib) == 1 && !chain.count(std::min(ia, ib) == ia ? a : b);
    if (consecutive) chain[std::min(ia, ib) == ia ? a : b] = rp;
    else loops.push_back(rp);
  }
  runtime::LogWriter out(out_lcm);
  int64_t seq_odo = 0, seq_loop = 0;
  SE3 pose;  // the composed chain, starting at the identity
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
  const auto active = pose_axes(planar);
  for (int i : active) cov(i, i) = 1e-9;
  // Loop closures are emitted when their later vertex's odometry has been sent.
  std::multimap<int64_t, const graph::RelativePoseFactor*> loops_by_time;
  for (const auto* rp : loops)
    loops_by_time.emplace(std::max(utime[rp->variables()[0]], utime[rp->variables()[1]]), rp);
  auto relative = [&](const graph::RelativePoseFactor* rp) { return planar ? rp->measurement2().to_se3() : rp->measurement3(); };
  for (size_t k = 0; k < order.size(); ++k) {
    const int v = order[k];
    engine::Odometry odo;
    odo.utime = utime[v];
    odo.source = o.source;
    odo.planar = planar;
    Eigen::Matrix<double, 6, 6> q = Eigen::Matrix<double, 6, 6>::Zero();
    for (int i : active) q(i, i) = 1e-9;
    if (k > 0) {
      const int prev = order[k - 1];
      auto it = chain.find(vars[static_cast<size_t>(prev)].id < vars[static_cast<size_t>(v)].id ? prev : v);
      if (it == chain.end() || (it->second->variables()[0] != prev && it->second->variables()[1] != prev))
        throw std::runtime_error(g2o_path + ": no odometry edge between vertices " + std::to_string(vars[static_cast<size_t>(prev)].id) +
                                 " and " + std::to_string(vars[static_cast<size_t>(v)].id) + " (the chain has a gap)");
      const auto* rp = it->second;
      SE3 delta = relative(rp);
      if (rp->variables()[0] != prev) delta = delta.inverse();
      const Eigen::Matrix<double, 6, 6> info = g2o_information_to_sextant(rp->information(), planar);
      for (int r : active)
        for (int c : active) q(r, c) = 0;
      Eigen::MatrixXd sub(active.size(), active.size());
      for (size_t r = 0; r < active.size(); ++r)
        for (size_t c = 0; c < active.size(); ++c) sub(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = info(active[r], active[c]);
      const Eigen::MatrixXd subcov = sub.inverse();
      for (size_t r = 0; r < active.size(); ++r)
        for (size_t c = 0; c < active.size(); ++c) q(active[r], active[c]) = subcov(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
      q = 0.5 * (q + q.transpose()).eval();
      const Eigen::Matrix<double, 6, 6> ad = delta.inverse().adjoint();
      cov = ad * cov * ad.transpose() + q;
      cov = 0.5 * (cov + cov.transpose()).eval();
      pose = pose * delta;
    }
    odo.pose.position = pose.translation();
    odo.pose.orientation = pose.rotation().quaternion();
    odo.covariance = cov;
    odo.increment_covariance = q;
    out.write(odo.utime, "ODOMETRY", runtime::to_message(odo, "sextant-convert", seq_odo++));
    ++result.odometry;
    auto range = loops_by_time.equal_range(odo.utime);
    for (auto it = range.first; it != range.second; ++it) {
      const auto* rp = it->second;
      engine::LoopClosure lc;
      lc.utime = odo.utime;
      lc.source = o.source;
      lc.planar = planar;
      lc.utime_from = utime[rp->variables()[0]];
      lc.utime_to = utime[rp->variables()[1]];
      const SE3 z = relative(rp);
      lc.relative.position = z.translation();
      lc.relative.orientation = z.rotation().quaternion();
      lc.information = g2o_information_to_sextant(rp->information(), planar);
      if (planar)
        for (int i : {2, 3, 4}) lc.information(i, i) = 1.0;  // unused components: unit information keeps it definite
      lc.matcher = "g2o";
      lc.score = 1.0;
      out.write(lc.utime, "LOOP_CLOSURES", runtime::to_message(lc, "sextant-convert", seq_loop++));
      ++result.loop_closures;
    }
  }
  out.flush();
  if (!gt_tum.empty()) {
    std::vector<StampedPose> poses;
    for (int v : order) {
      const SE3 x = vars[static_cast<size_t>(v)].as_se3();
      poses.push_back({static_cast<double>(utime[v]) * 1e-6, {x.translation(), x.rotation().quaternion()}});
    }
    write_tum(gt_tum, poses);
  }
  return result;
}

}  // namespace sextant::tools
