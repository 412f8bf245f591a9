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

namespace {

// One g2o file's conversion: pose vertices in id order get times `period_us` apart; the first edge (in file order)
// between consecutive ids is the odometry chain, composed into odometry messages; every other pose edge is a loop
// closure, sent once the odometry of its later vertex has been.
class G2oConverter {
 public:
  G2oConverter(const std::string& g2o_path, const G2oConversionOptions& o)
      : path_(g2o_path),
        o_(o),
        file_(graph::read_g2o(g2o_path)),
        vars_(file_.graph.variables()),
        planar_(file_.dimension == 2),
        active_(pose_axes(planar_)) {}

  G2oConversion convert(const std::string& out_lcm, const std::string& gt_tum) {
    order_vertices();
    split_chain_and_loops();
    runtime::LogWriter out(out_lcm);
    for (int i : active_) cov_(i, i) = 1e-9;
    for (size_t k = 0; k < order_.size(); ++k) {
      write_odometry(out, k);
      write_loops_at(out, utime_[order_[k]]);
    }
    out.flush();
    if (!gt_tum.empty()) write_ground_truth(gt_tum);
    return result_;
  }

 private:
  // Vertex times by id order.
  void order_vertices() {
    for (size_t i = 0; i < vars_.size(); ++i)
      if (vars_[i].is_pose()) order_.push_back(static_cast<int>(i));
    std::sort(order_.begin(), order_.end(),
              [&](int a, int b) { return vars_[static_cast<size_t>(a)].id < vars_[static_cast<size_t>(b)].id; });
    for (size_t k = 0; k < order_.size(); ++k)
      utime_[order_[k]] = o_.start_utime + static_cast<int64_t>(k) * o_.period_us;
  }

  // The odometry chain: for each vertex, the first edge (in file order) to the next id; the other pose edges are
  // loops, by the time of their later vertex; edges that are not between poses are counted and skipped.
  void split_chain_and_loops() {
    for (const auto& f : file_.graph.factors()) {
      const auto* rp = dynamic_cast<const graph::RelativePoseFactor*>(f.get());
      if (rp == nullptr) {
        ++result_.skipped_edges;
        continue;
      }
      const int a = rp->variables()[0], b = rp->variables()[1];
      const int64_t ia = vars_[static_cast<size_t>(a)].id, ib = vars_[static_cast<size_t>(b)].id;
      const bool consecutive = std::abs(ia - ib) == 1 && !chain_.count(std::min(ia, ib) == ia ? a : b);
      if (consecutive)
        chain_[std::min(ia, ib) == ia ? a : b] = rp;
      else
        loops_by_time_.emplace(std::max(utime_[a], utime_[b]), rp);
    }
  }

  SE3 relative(const graph::RelativePoseFactor* rp) const {
    return planar_ ? rp->measurement2().to_se3() : rp->measurement3();
  }

  // The increment covariance of a chain edge: its information (in sextant's tangent) inverted on the active axes.
  Eigen::Matrix<double, 6, 6> increment_covariance(const graph::RelativePoseFactor* rp) const {
    Eigen::Matrix<double, 6, 6> q = Eigen::Matrix<double, 6, 6>::Zero();
    for (int i : active_) q(i, i) = 1e-9;
    const Eigen::Matrix<double, 6, 6> info = g2o_information_to_sextant(rp->information(), planar_);
    for (int r : active_)
      for (int c : active_) q(r, c) = 0;
    Eigen::MatrixXd sub(active_.size(), active_.size());
    for (size_t r = 0; r < active_.size(); ++r)
      for (size_t c = 0; c < active_.size(); ++c)
        sub(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = info(active_[r], active_[c]);
    const Eigen::MatrixXd subcov = sub.inverse();
    for (size_t r = 0; r < active_.size(); ++r)
      for (size_t c = 0; c < active_.size(); ++c)
        q(active_[r], active_[c]) = subcov(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c));
    q = 0.5 * (q + q.transpose()).eval();
    return q;
  }

  // The k-th vertex's odometry message: the chain composed up to it (pose and covariance), with the increment from
  // the previous vertex.
  void write_odometry(runtime::LogWriter& out, size_t k) {
    const int v = order_[k];
    engine::Odometry odo;
    odo.utime = utime_[v];
    odo.source = o_.source;
    odo.planar = planar_;
    Eigen::Matrix<double, 6, 6> q = Eigen::Matrix<double, 6, 6>::Zero();
    for (int i : active_) q(i, i) = 1e-9;
    if (k > 0) {
      const int prev = order_[k - 1];
      auto it = chain_.find(vars_[static_cast<size_t>(prev)].id < vars_[static_cast<size_t>(v)].id ? prev : v);
      if (it == chain_.end() || (it->second->variables()[0] != prev && it->second->variables()[1] != prev))
        throw std::runtime_error(path_ + ": no odometry edge between vertices " +
                                 std::to_string(vars_[static_cast<size_t>(prev)].id) + " and " +
                                 std::to_string(vars_[static_cast<size_t>(v)].id) + " (the chain has a gap)");
      const auto* rp = it->second;
      SE3 delta = relative(rp);
      if (rp->variables()[0] != prev) delta = delta.inverse();
      q = increment_covariance(rp);
      const Eigen::Matrix<double, 6, 6> ad = delta.inverse().adjoint();
      cov_ = ad * cov_ * ad.transpose() + q;
      cov_ = 0.5 * (cov_ + cov_.transpose()).eval();
      pose_ = pose_ * delta;
    }
    odo.pose.position = pose_.translation();
    odo.pose.orientation = pose_.rotation().quaternion();
    odo.covariance = cov_;
    odo.increment_covariance = q;
    out.write(odo.utime, "ODOMETRY", runtime::to_message(odo, "sextant-convert", seq_odo_++));
    ++result_.odometry;
  }

  // The loop closures whose later vertex is at `utime`.
  void write_loops_at(runtime::LogWriter& out, int64_t utime) {
    auto range = loops_by_time_.equal_range(utime);
    for (auto it = range.first; it != range.second; ++it) {
      const auto* rp = it->second;
      engine::LoopClosure lc;
      lc.utime = utime;
      lc.source = o_.source;
      lc.planar = planar_;
      lc.utime_from = utime_[rp->variables()[0]];
      lc.utime_to = utime_[rp->variables()[1]];
      const SE3 z = relative(rp);
      lc.relative.position = z.translation();
      lc.relative.orientation = z.rotation().quaternion();
      lc.information = g2o_information_to_sextant(rp->information(), planar_);
      if (planar_)
        for (int i : {2, 3, 4}) lc.information(i, i) = 1.0;  // unused components: unit information keeps it definite
      lc.matcher = "g2o";
      lc.score = 1.0;
      out.write(lc.utime, "LOOP_CLOSURES", runtime::to_message(lc, "sextant-convert", seq_loop_++));
      ++result_.loop_closures;
    }
  }

  // The file's vertex estimates at their times, as the ground truth.
  void write_ground_truth(const std::string& gt_tum) {
    std::vector<StampedPose> poses;
    for (int v : order_) {
      const SE3 x = vars_[static_cast<size_t>(v)].as_se3();
      poses.push_back({static_cast<double>(utime_[v]) * 1e-6, {x.translation(), x.rotation().quaternion()}});
    }
    write_tum(gt_tum, poses);
  }

  const std::string& path_;
  const G2oConversionOptions& o_;
  const graph::G2oGraph file_;
  const std::vector<graph::Variable>& vars_;
  const bool planar_;
  const std::span<const int> active_;
  std::vector<int> order_;                                 // pose vertices by id
  std::map<int, int64_t> utime_;                           // by vertex index
  std::map<int, const graph::RelativePoseFactor*> chain_;  // from vertex index -> edge
  std::multimap<int64_t, const graph::RelativePoseFactor*> loops_by_time_;
  G2oConversion result_;
  int64_t seq_odo_ = 0, seq_loop_ = 0;
  SE3 pose_;  // the composed chain, starting at the identity
  Eigen::Matrix<double, 6, 6> cov_ = Eigen::Matrix<double, 6, 6>::Zero();
};

}  // namespace

G2oConversion convert_g2o(const std::string& g2o_path, const std::string& out_lcm, const std::string& gt_tum,
                          const G2oConversionOptions& o) {
  return G2oConverter(g2o_path, o).convert(out_lcm, gt_tum);
}

}  // namespace sextant::tools
