#include "estimators/graph/initialization.hpp"

#include "estimators/graph/block_ordering.hpp"

#include <Eigen/SVD>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <queue>
#include <tuple>
#include <map>
#include <random>
#include <cstdint>

namespace sextant::graph {
namespace {

struct PoseEdge {
  int i, j;
  const RelativePoseFactor* f;
};

std::vector<PoseEdge> pose_edges(const FactorGraph& g) {
  std::vector<PoseEdge> out;
  for (const auto& f : g.factors())
    if (const auto* rp = dynamic_cast<const RelativePoseFactor*>(f.get()))
      out.push_back({rp->variables()[0], rp->variables()[1], rp});
  return out;
}

void place_points(FactorGraph& g, const std::vector<bool>& known) {
  auto& vars = g.variables();
  std::vector<bool> placed(vars.size(), false);
  for (const auto& f : g.factors()) {
    const auto* po = dynamic_cast<const PointObservationFactor*>(f.get());
    if (!po || po->model() != PointObservationFactor::Model::kPosition) continue;
    const int pose = po->variables()[0], point = po->variables()[1];
    if (!known[static_cast<size_t>(pose)] || placed[static_cast<size_t>(point)] ||
        vars[static_cast<size_t>(point)].fixed)
      continue;
    const auto& x = vars[static_cast<size_t>(pose)];
    const auto& z = po->measurement();
    if (x.kind == VariableKind::kPose2)
      vars[static_cast<size_t>(point)].point.head<2>() = x.pose2.act(z.head<2>());
    else
      vars[static_cast<size_t>(point)].point = x.pose3 * Eigen::Vector3d(z[0], z[1], z[2]);
    placed[static_cast<size_t>(point)] = true;
  }
}

// Projection of a d x d matrix onto SO(d): U diag(1, ..., det(U V')) V'.
template <int D>
Eigen::Matrix<double, D, D> project_to_so(const Eigen::Matrix<double, D, D>& M) {
  Eigen::JacobiSVD<Eigen::Matrix<double, D, D>> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix<double, D, D> S = Eigen::Matrix<double, D, D>::Identity();
  S(D - 1, D - 1) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
  return svd.matrixU() * S * svd.matrixV().transpose();
}

// The chordal relaxation (Carlone et al., ICRA 2015) of the poses of g: rotations first, as a linear least-squares
// problem over vec(R) projected onto SO(D), then translations given them; each a sparse LDL' solve.
template <int D>
class ChordalRelaxation {
 public:
  using MatD = Eigen::Matrix<double, D, D>;
  using VecD = Eigen::Matrix<double, D, 1>;

  explicit ChordalRelaxation(FactorGraph& g) : g_(g), vars_(g.variables()), edges_(pose_edges(g)) {}

  /// Initializes the unknown poses (and the points seen from them); returns why it could not, or "".
  std::string run() {
    if (number_unknown_poses() == 0) return "";
    order_unknown_poses();
    if (!solve_rotations()) return "chordal relaxation: the rotation system is singular (disconnected graph?)";
    if (!solve_translations()) return "chordal relaxation: the translation system is singular (disconnected graph?)";
    std::vector<bool> known(vars_.size(), true);
    place_points(g_, known);
    return "";
  }

 private:
  MatD rotation(int v) const {
    if constexpr (D == 2)
      return vars_[static_cast<size_t>(v)].pose2.rotation().matrix();
    else
      return vars_[static_cast<size_t>(v)].pose3.rotation().matrix();
  }
  VecD translation(int v) const {
    if constexpr (D == 2)
      return vars_[static_cast<size_t>(v)].pose2.translation();
    else
      return vars_[static_cast<size_t>(v)].pose3.translation();
  }

  // Unknown poses numbered 0..n-1 in index_; the gauge (fixed poses, else the first pose) stays.
  int number_unknown_poses() {
    index_.assign(vars_.size(), -1);
    bool any_fixed = false;
    for (const auto& v : vars_) any_fixed = any_fixed || (v.fixed && v.is_pose());
    bool gauge_taken = any_fixed;
    for (size_t v = 0; v < vars_.size(); ++v) {
      if (!vars_[v].is_pose() || vars_[v].fixed) continue;
      if (!gauge_taken) {
        gauge_taken = true;
        continue;
      }
      index_[v] = n_++;
    }
    return n_;
  }

  // Scalar weights from the information blocks (SE-Sync's isotropic approximation).
  // Fixed-size blocks: their inverses are closed forms, not a dynamic LU per edge.
  static void weights(const RelativePoseFactor* f, double& kappa, double& tau) {
    const Eigen::MatrixXd& I = f->information();
    tau = D / MatD(I.template topLeftCorner<D, D>()).inverse().trace();
    if constexpr (D == 2)
      kappa = I(2, 2);
    else
      kappa = 3.0 / (2.0 * Eigen::Matrix3d(I.template bottomRightCorner<3, 3>()).inverse().trace());
  }

  // Rotations: unknowns R_i, residual R_j - R_i Z_ij weighted by kappa.  Row r of the residual,
  // x_j - Z' x_i with x = R(r, :)', involves row r of each rotation only, and every row has the same normal matrix:
  // one sparse LDL' of an (n D) x (n D) matrix with D right-hand sides (column r for row r) instead of one of
  // (n D^2) x (n D^2).  Solved, then projected onto SO(D) into R_; false when the system is singular.
  bool solve_rotations() {
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n_ * D, D);
    for (const auto& e : edges_) {
      double kappa, tau;
      weights(e.f, kappa, tau);
      MatD Z;
      if constexpr (D == 2)
        Z = e.f->measurement2().rotation().matrix();
      else
        Z = e.f->measurement3().rotation().matrix();
      const int ii = index_[static_cast<size_t>(e.i)], jj = index_[static_cast<size_t>(e.j)];
      // kappa |x_j - Z' x_i|^2: H += kappa [Z Z' = I, -Z; -Z', I] over (i, j); a known end moves to the right.
      if (ii >= 0) {
        for (int a = 0; a < D; ++a) trip.emplace_back(ii * D + a, ii * D + a, kappa);
        if (jj < 0) rhs.template block<D, D>(ii * D, 0) += kappa * Z * rotation(e.j).transpose();
      }
      if (jj >= 0) {
        for (int a = 0; a < D; ++a) trip.emplace_back(jj * D + a, jj * D + a, kappa);
        if (ii < 0) rhs.template block<D, D>(jj * D, 0) += kappa * Z.transpose() * rotation(e.i).transpose();
      }
      if (ii >= 0 && jj >= 0)  // the lower triangle only: the block below the diagonal
        for (int a = 0; a < D; ++a)
          for (int b = 0; b < D; ++b) {
            if (ii > jj)
              trip.emplace_back(ii * D + a, jj * D + b, -kappa * Z(a, b));
            else
              trip.emplace_back(jj * D + b, ii * D + a, -kappa * Z(a, b));
          }
    }
    Eigen::MatrixXd x;
    if (!solve_sparse(n_ * D, trip, rhs, x)) return false;
    R_.resize(vars_.size());
    for (size_t v = 0; v < vars_.size(); ++v) {
      if (!vars_[v].is_pose()) continue;
      R_[v] = index_[v] >= 0 ? project_to_so<D>(x.template block<D, D>(index_[v] * D, 0).transpose())
                             : rotation(static_cast<int>(v));
    }
    return true;
  }

  // Translations: t_j - t_i = R_i t_ij weighted by tau (isotropic), so each coordinate is its own problem with the
  // same matrix, the graph's weighted Laplacian over the unknown poses: one n x n LDL' with D right-hand sides.
  // Written with R_ into the unknown poses; false when the system is singular.
  bool solve_translations() {
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n_, D);
    for (const auto& e : edges_) {
      double kappa, tau;
      weights(e.f, kappa, tau);
      VecD tij;
      if constexpr (D == 2)
        tij = e.f->measurement2().translation();
      else
        tij = e.f->measurement3().translation();
      const VecD c = R_[static_cast<size_t>(e.i)] * tij;
      const int ii = index_[static_cast<size_t>(e.i)], jj = index_[static_cast<size_t>(e.j)];
      if (ii >= 0) {
        trip.emplace_back(ii, ii, tau);
        rhs.row(ii) -= tau * (jj >= 0 ? c : VecD(c - translation(e.j))).transpose();
      }
      if (jj >= 0) {
        trip.emplace_back(jj, jj, tau);
        rhs.row(jj) += tau * (ii >= 0 ? c : VecD(c + translation(e.i))).transpose();
      }
      if (ii >= 0 && jj >= 0) trip.emplace_back(std::max(ii, jj), std::min(ii, jj), -tau);  // lower triangle
    }
    Eigen::MatrixXd t;
    if (!solve_sparse(n_, trip, rhs, t)) return false;
    for (size_t v = 0; v < vars_.size(); ++v) {
      if (index_[v] < 0) continue;
      const VecD tv = t.row(index_[v]).transpose();
      if constexpr (D == 2)
        vars_[v].pose2 = SE2(SO2(std::atan2(R_[v](1, 0), R_[v](0, 0))), tv);
      else
        vars_[v].pose3 = SE3(SO3(Eigen::Matrix3d(R_[v])), tv);
    }
    return true;
  }

  // Renumbers the unknown poses in an approximate minimum degree order of the pose graph (block_amd_order on its
  // Laplacian's pattern), so that both systems factor as they are numbered: the translations' is that Laplacian, the
  // rotations' its block expansion.  One ordering for both, on the smaller pattern.
  void order_unknown_poses() {
    std::vector<std::vector<int>> upper(static_cast<size_t>(n_));
    for (int k = 0; k < n_; ++k) upper[static_cast<size_t>(k)].push_back(k);
    for (const auto& e : edges_) {
      const int ii = index_[static_cast<size_t>(e.i)], jj = index_[static_cast<size_t>(e.j)];
      if (ii >= 0 && jj >= 0 && ii != jj) upper[static_cast<size_t>(std::max(ii, jj))].push_back(std::min(ii, jj));
    }
    for (auto& r : upper) {
      std::sort(r.begin(), r.end());
      r.erase(std::unique(r.begin(), r.end()), r.end());
    }
    cholmod_common common;
    cholmod_start(&common);
    std::vector<int> order;  // order[k]: the k-th eliminated
    try {
      order = block_amd_order(upper, common);
    } catch (const std::runtime_error&) {
      order.clear();  // CHOLMOD out of memory: the numbering as it is (same answer, more fill)
    }
    cholmod_finish(&common);
    if (order.size() != static_cast<size_t>(n_)) return;
    std::vector<int> position(static_cast<size_t>(n_));
    for (int k = 0; k < n_; ++k) position[static_cast<size_t>(order[static_cast<size_t>(k)])] = k;
    for (int& i : index_)
      if (i >= 0) i = position[static_cast<size_t>(i)];
  }

  // x = H^-1 rhs for the symmetric H given by the lower triangle in `trip` (size x size, duplicates summed), factored
  // in its own numbering (order_unknown_poses chose it); false when H is singular.
  static bool solve_sparse(int size, const std::vector<Eigen::Triplet<double>>& trip, const Eigen::MatrixXd& rhs,
                           Eigen::MatrixXd& x) {
    Eigen::SparseMatrix<double> H(size, size);
    H.setFromTriplets(trip.begin(), trip.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> chol(H);
    if (chol.info() != Eigen::Success) return false;
    x = chol.solve(rhs);
    return chol.info() == Eigen::Success && x.allFinite();
  }

  FactorGraph& g_;
  std::vector<Variable>& vars_;
  const std::vector<PoseEdge> edges_;
  std::vector<int> index_;  // per variable: its unknown's number, or -1
  int n_ = 0;               // unknown poses
  std::vector<MatD> R_;     // per variable: the rotation (solved or known)
};

template <int D>
std::string chordal(FactorGraph& g) {
  return ChordalRelaxation<D>(g).run();
}

// Range-add of a linear ramp over pose indices, point query: poses a+1..b get c * (j - a), poses after b get
// c * (b - a).  Two Fenwick trees over "add c*j + d for j >= k" (Olson's incremental parameterization).
class RampTree {
 public:
  explicit RampTree(size_t n) : slope_(n + 1, Eigen::Vector3d::Zero()), offset_(n + 1, Eigen::Vector3d::Zero()) {}
  /// Adds c*(j - a) for a < j <= b and c*(b - a) for j > b.
  void add_ramp(size_t a, size_t b, const Eigen::Vector3d& c) {
    add(a + 1, c, -c * static_cast<double>(a));
    add(b + 1, -c, c * static_cast<double>(b));
  }
  Eigen::Vector3d at(size_t j) const {
    Eigen::Vector3d s = Eigen::Vector3d::Zero(), o = Eigen::Vector3d::Zero();
    for (size_t i = j + 1; i > 0; i -= i & (~i + 1)) s += slope_[i], o += offset_[i];
    return s * static_cast<double>(j) + o;
  }

 private:
  void add(size_t k, const Eigen::Vector3d& s, const Eigen::Vector3d& o) {
    for (size_t i = k + 1; i < slope_.size(); i += i & (~i + 1)) slope_[i] += s, offset_[i] += o;
  }
  std::vector<Eigen::Vector3d> slope_, offset_;
};

}  // namespace

bool initialize_auto(FactorGraph& g) {
  const double before = g.chi2();
  const std::vector<Variable> saved = g.variables();
  if (!initialize_chordal(g).empty()) return false;  // left as it was
  const double after = g.chi2();
  if (std::isfinite(after) && after < before) return true;
  g.variables() = saved;
  return false;
}

std::string initialize_sgd(FactorGraph& g, int sweeps, uint64_t seed) {
  auto& vars = g.variables();
  std::vector<int> poses;
  for (size_t v = 0; v < vars.size(); ++v) {
    if (vars[v].kind == VariableKind::kPose3)
      return "SGD initialization supports planar graphs; use --init chordal for 3-D";
    if (vars[v].kind == VariableKind::kPose2) poses.push_back(static_cast<int>(v));
  }
  if (poses.size() < 2) return "";
  // Chain order by id; each pose's index in Olson's parameterization.
  std::sort(poses.begin(), poses.end(),
            [&](int a, int b) { return vars[static_cast<size_t>(a)].id < vars[static_cast<size_t>(b)].id; });
  std::vector<int> rank(vars.size(), -1);
  for (size_t k = 0; k < poses.size(); ++k) rank[static_cast<size_t>(poses[k])] = static_cast<int>(k);
  const auto edges = pose_edges(g);
  if (edges.empty()) return "";
  // Base poses (x, y, theta with theta unwrapped along the chain) plus the accumulated corrections.
  std::vector<Eigen::Vector3d> base(poses.size());
  for (size_t k = 0; k < poses.size(); ++k) {
    const SE2& x = vars[static_cast<size_t>(poses[k])].pose2;
    double th = x.angle();
    if (k > 0) th = base[k - 1].z() + wrap_angle(th - base[k - 1].z());
    base[k] = {x.translation().x(), x.translation().y(), th};
  }
  RampTree tree(poses.size());
  auto pose_at = [&](size_t k) { return Eigen::Vector3d(base[k] + tree.at(k)); };
  // The median information per dimension normalizes each constraint's step.
  Eigen::Vector3d median;
  for (int d = 0; d < 3; ++d) {
    std::vector<double> w;
    for (const auto& e : edges) w.push_back(e.f->information()(d, d));
    std::nth_element(w.begin(), w.begin() + static_cast<std::ptrdiff_t>(w.size() / 2), w.end());
    median[d] = std::max(w[w.size() / 2], 1e-12);
  }
  std::vector<size_t> order(edges.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::mt19937_64 rng(seed);
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    const double alpha = 1.0 / (1.0 + sweep);
    std::shuffle(order.begin(), order.end(), rng);
    for (size_t idx : order) {
      const auto& e = edges[idx];
      size_t a = static_cast<size_t>(rank[static_cast<size_t>(e.i)]),
             b = static_cast<size_t>(rank[static_cast<size_t>(e.j)]);
      SE2 z = e.f->measurement2();
      if (a > b) std::swap(a, b), z = z.inverse();
      if (a == b) continue;
      const Eigen::Vector3d pa = pose_at(a), pb = pose_at(b);
      const SE2 xa(pa.x(), pa.y(), pa.z());
      const SE2 pred = xa * z;
      Eigen::Vector3d r(pred.translation().x() - pb.x(), pred.translation().y() - pb.y(),
                        wrap_angle(pred.angle() - pb.z()));
      // Information in the global frame (translation block rotated by theta_a).
      Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
      R.topLeftCorner<2, 2>() = xa.rotation().matrix();
      const Eigen::Matrix3d W = R * e.f->information() * R.transpose();
      Eigen::Vector3d step;
      for (int d = 0; d < 3; ++d) step[d] = alpha * W(d, d) / (W(d, d) + median[d]) * r[d];
      tree.add_ramp(a, b, step / static_cast<double>(b - a));
    }
  }
  for (size_t k = 0; k < poses.size(); ++k) {
    const Eigen::Vector3d p = pose_at(k);
    vars[static_cast<size_t>(poses[k])].pose2 = SE2(p.x(), p.y(), p.z());
  }
  std::vector<bool> known(vars.size(), true);
  place_points(g, known);
  return "";
}

int initialize_by_odometry(FactorGraph& g) {
  auto& vars = g.variables();
  std::vector<bool> known(vars.size(), false);
  // Roots: fixed poses, else the pose with the lowest id at the identity... kept at its current value.
  int root = -1;
  for (size_t v = 0; v < vars.size(); ++v) {
    if (!vars[v].is_pose()) continue;
    if (vars[v].fixed) known[v] = true;
    if (root < 0 || vars[v].id < vars[static_cast<size_t>(root)].id) root = static_cast<int>(v);
  }
  if (root < 0) return 0;
  if (std::none_of(known.begin(), known.end(), [](bool b) { return b; })) known[static_cast<size_t>(root)] = true;
  // Prim's spanning tree with edge weight |id_i - id_j| (ties: file order): the chain of consecutive ids is used
  // wherever it exists, exactly as "compose the odometry" does, and loop closures only bridge its gaps.
  const auto edges = pose_edges(g);
  std::vector<std::vector<size_t>> adj(vars.size());
  for (size_t k = 0; k < edges.size(); ++k) {
    adj[static_cast<size_t>(edges[k].i)].push_back(k);
    adj[static_cast<size_t>(edges[k].j)].push_back(k);
  }
  using Item = std::tuple<int64_t, size_t, int>;  // (gap, edge, known endpoint)
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> frontier;
  auto expand = [&](int u) {
    for (size_t k : adj[static_cast<size_t>(u)]) {
      const auto& e = edges[k];
      const int w = e.i == u ? e.j : e.i;
      if (!known[static_cast<size_t>(w)])
        frontier.emplace(std::abs(vars[static_cast<size_t>(e.i)].id - vars[static_cast<size_t>(e.j)].id), k, u);
    }
  };
  for (size_t v = 0; v < vars.size(); ++v)
    if (known[v]) expand(static_cast<int>(v));
  while (!frontier.empty()) {
    const auto [gap, k, u] = frontier.top();
    frontier.pop();
    const auto& e = edges[k];
    const int w = e.i == u ? e.j : e.i;
    if (known[static_cast<size_t>(w)]) continue;
    auto& x = vars[static_cast<size_t>(w)];
    const auto& xu = vars[static_cast<size_t>(u)];
    if (e.f->planar())
      x.pose2 = e.i == u ? xu.pose2 * e.f->measurement2() : xu.pose2 * e.f->measurement2().inverse();
    else
      x.pose3 = e.i == u ? xu.pose3 * e.f->measurement3() : xu.pose3 * e.f->measurement3().inverse();
    known[static_cast<size_t>(w)] = true;
    expand(w);
  }
  place_points(g, known);
  int unreached = 0;
  for (size_t v = 0; v < vars.size(); ++v) unreached += vars[v].is_pose() && !known[v];
  return unreached;
}

std::string initialize_chordal(FactorGraph& g) {
  bool planar = false, spatial = false;
  for (const auto& v : g.variables())
    planar |= v.kind == VariableKind::kPose2, spatial |= v.kind == VariableKind::kPose3;
  if (planar && spatial) return "chordal relaxation: the graph mixes 2-D and 3-D poses";
  const auto backup = g.variables();
  const std::string why = spatial ? chordal<3>(g) : chordal<2>(g);
  if (!why.empty()) g.variables() = backup;
  return why;
}

}  // namespace sextant::graph
