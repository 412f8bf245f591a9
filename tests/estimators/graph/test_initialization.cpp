// The chordal initialization against the relaxation written out densely (one unknown per entry of every rotation,
// as the paper states it), on a planar and a spatial graph.
#include "estimators/graph/g2o_io.hpp"
#include "estimators/graph/initialization.hpp"

#include <Eigen/Dense>
#include <doctest/doctest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

using namespace sextant;
using namespace sextant::graph;

namespace {

std::string data(const std::string& name) { return std::string(SEXTANT_SHARED_DIR) + "/data/posegraph/" + name; }

// The lines of a g2o file whose ids are all below `n` (the first n vertices and the edges among them).
G2oGraph first_vertices(const std::string& name, int n) {
  std::ifstream in(data(name));
  std::ostringstream kept;
  for (std::string line; std::getline(in, line);) {
    std::istringstream s(line);
    std::string tag;
    int a = 0, b = 0;
    s >> tag >> a;
    const bool edge = tag.rfind("EDGE", 0) == 0;
    if (edge) s >> b;
    if (a < n && (!edge || b < n)) kept << line << "\n";
  }
  std::istringstream text(kept.str());
  return read_g2o(text, name);
}

template <int D>
struct Relaxation {
  using MatD = Eigen::Matrix<double, D, D>;
  std::vector<MatD> R;
  std::vector<Eigen::Matrix<double, D, 1>> t;
};

// Chordal relaxation (Carlone et al., ICRA 2015; SE-Sync's isotropic weights) over every pose but the first, dense:
// min sum kappa |vec(R_j) - (Z' (x) I) vec(R_i)|^2, each R projected onto SO(D), then
// min sum tau |t_j - t_i - R_i t_ij|^2.
template <int D>
Relaxation<D> dense_chordal(const FactorGraph& g) {
  using MatD = Eigen::Matrix<double, D, D>;
  const int n = static_cast<int>(g.variables().size()) - 1, q = D * D;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n * q, n * q), Ht = Eigen::MatrixXd::Zero(n * D, n * D);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n * q), bt = Eigen::VectorXd::Zero(n * D);
  const auto rotation0 = [&] {
    if constexpr (D == 2)
      return MatD(g.variables()[0].pose2.rotation().matrix());
    else
      return MatD(g.variables()[0].pose3.rotation().matrix());
  }();
  const auto translation0 = [&] {
    if constexpr (D == 2)
      return Eigen::Matrix<double, D, 1>(g.variables()[0].pose2.translation());
    else
      return Eigen::Matrix<double, D, 1>(g.variables()[0].pose3.translation());
  }();
  struct Edge {
    int i, j;
    MatD Z;
    Eigen::Matrix<double, D, 1> tij;
    double kappa, tau;
  };
  std::vector<Edge> edges;
  for (const auto& f : g.factors()) {
    const auto* rp = dynamic_cast<const RelativePoseFactor*>(f.get());
    if (!rp) continue;
    Edge e{rp->variables()[0] - 1, rp->variables()[1] - 1, MatD(), {}, 0, 0};
    const Eigen::MatrixXd& I = rp->information();
    if constexpr (D == 2) {
      e.Z = rp->measurement2().rotation().matrix(), e.tij = rp->measurement2().translation();
      e.kappa = I(2, 2);
    } else {
      e.Z = rp->measurement3().rotation().matrix(), e.tij = rp->measurement3().translation();
      e.kappa = 3.0 / (2.0 * I.bottomRightCorner(3, 3).inverse().trace());
    }
    e.tau = D / I.topLeftCorner(D, D).inverse().trace();
    edges.push_back(e);
  }
  for (const auto& e : edges) {
    // Residual rows: A_j vec(R_j) - A_i vec(R_i) with A_j = I, A_i = Z' (x) I; pose -1 is the known first pose.
    Eigen::MatrixXd Ai(q, q), Aj = Eigen::MatrixXd::Identity(q, q);
    for (int c = 0; c < D; ++c)
      for (int k = 0; k < D; ++k) Ai.block(c * D, k * D, D, D) = e.Z(k, c) * MatD::Identity();
    Eigen::VectorXd known = Eigen::VectorXd::Zero(q);
    if (e.i < 0) known -= Ai * Eigen::Map<const Eigen::VectorXd>(rotation0.data(), q);
    if (e.j < 0) known += Eigen::Map<const Eigen::VectorXd>(rotation0.data(), q);
    for (const auto& [u, Au] : {std::pair{e.i, Eigen::MatrixXd(-Ai)}, std::pair{e.j, Aj}}) {
      if (u < 0) continue;
      b.segment(u * q, q) -= e.kappa * Au.transpose() * known;
      for (const auto& [w, Aw] : {std::pair{e.i, Eigen::MatrixXd(-Ai)}, std::pair{e.j, Aj}})
        if (w >= 0) H.block(u * q, w * q, q, q) += e.kappa * Au.transpose() * Aw;
    }
  }
  const Eigen::VectorXd r = H.ldlt().solve(b);
  Relaxation<D> out;
  out.R.push_back(rotation0);
  for (int v = 0; v < n; ++v) {
    Eigen::JacobiSVD<MatD> svd(Eigen::Map<const MatD>(r.data() + v * q), Eigen::ComputeFullU | Eigen::ComputeFullV);
    MatD S = MatD::Identity();
    S(D - 1, D - 1) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1 : 1;
    out.R.push_back(svd.matrixU() * S * svd.matrixV().transpose());
  }
  for (const auto& e : edges) {
    const Eigen::Matrix<double, D, 1> c = out.R[static_cast<size_t>(e.i + 1)] * e.tij;
    // Residual t_j - t_i - c.
    Eigen::Matrix<double, D, 1> known = -c;
    if (e.i < 0) known -= translation0;
    if (e.j < 0) known += translation0;
    for (const auto& [u, su] : {std::pair{e.i, -1.0}, std::pair{e.j, 1.0}}) {
      if (u < 0) continue;
      bt.segment(u * D, D) -= e.tau * su * known;
      for (const auto& [w, sw] : {std::pair{e.i, -1.0}, std::pair{e.j, 1.0}})
        if (w >= 0) Ht.block(u * D, w * D, D, D) += e.tau * su * sw * MatD::Identity();
    }
  }
  const Eigen::VectorXd tv = Ht.ldlt().solve(bt);
  out.t.push_back(translation0);
  for (int v = 0; v < n; ++v) out.t.push_back(tv.segment(v * D, D));
  return out;
}

}  // namespace

TEST_CASE("chordal initialization equals the dense relaxation on a planar and a spatial graph") {
  SUBCASE("planar: intel's first 120 poses") {
    auto g = first_vertices("intel.g2o", 120);
    REQUIRE(g.graph.variables().size() == 120);
    const auto want = dense_chordal<2>(g.graph);
    REQUIRE(initialize_chordal(g.graph).empty());
    double worst = 0;
    for (size_t v = 0; v < 120; ++v) {
      const auto& x = g.graph.variables()[v].pose2;
      worst = std::max({worst, (x.rotation().matrix() - want.R[v]).norm(), (x.translation() - want.t[v]).norm()});
    }
    CHECK(worst < 1e-8);
  }
  SUBCASE("spatial: smallGrid3D") {
    auto g = read_g2o(data("smallGrid3D.g2o"));
    const auto want = dense_chordal<3>(g.graph);
    REQUIRE(initialize_chordal(g.graph).empty());
    double worst = 0;
    for (size_t v = 0; v < g.graph.variables().size(); ++v) {
      const auto& x = g.graph.variables()[v].pose3;
      worst = std::max({worst, (x.rotation().matrix() - want.R[v]).norm(), (x.translation() - want.t[v]).norm()});
    }
    CHECK(worst < 1e-8);
  }
}
