#include "estimators/graph/smoother/marginal_covariance.hpp"

#include "estimators/spd_matrix.hpp"

#include <algorithm>
#include <vector>

namespace sextant::graph::smoother {

Eigen::MatrixXd marginal_covariance(SmootherState& s, int index) {
  const Factorization& fx = s.fx;
  const int p = s.pos[static_cast<size_t>(index)];
  if (fx.L == nullptr || p < 0) return {};
  const int d = s.graph.variables()[static_cast<size_t>(index)].dim();
  // H = L D L' (L unit lower triangular, D on L's diagonal), so the block of H^-1 at columns p..p+d-1 is
  // E' L^-T D^-1 L^-1 E = Y' D^-1 Y with Y = L^-1 E, E = [e_p .. e_p+d-1].  Column k of Y is nonzero only on the
  // path from p + k to the root of L's elimination tree, and the columns of one variable lie on one path, so the
  // forward solve walks that path alone: the cost is the path's nonzeros, not L's.
  const int* Lp = static_cast<const int*>(fx.L->p);
  const int* Li = static_cast<const int*>(fx.L->i);
  const int* Lnz = static_cast<const int*>(fx.L->nz);
  const double* Lx = static_cast<const double*>(fx.L->x);
  std::vector<int> path;
  for (int j = p; j != -1; j = fx.parent_of(j)) path.push_back(j);
  for (int k = 1; k < d; ++k)  // the variable's other columns: on p's path when its block is dense (always, in L)
    if (std::find(path.begin(), path.end(), p + k) == path.end()) return {};
  std::vector<int>& slot = s.marginal_slot;
  if (slot.size() < static_cast<size_t>(fx.capacity)) slot.assign(static_cast<size_t>(fx.capacity), -1);
  for (size_t r = 0; r < path.size(); ++r) slot[static_cast<size_t>(path[r])] = static_cast<int>(r);
  std::vector<double> Y(path.size() * static_cast<size_t>(d), 0.0);  // row r: Y's row at column path[r]
  const size_t ud = static_cast<size_t>(d);
  for (int k = 0; k < d; ++k)
    Y[static_cast<size_t>(slot[static_cast<size_t>(p + k)]) * ud + static_cast<size_t>(k)] = 1.0;
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(d, d);
  bool ok = true;
  for (size_t r = 0; r < path.size(); ++r) {
    const int j = path[r];
    const double dj = Lx[Lp[j]];
    if (!(dj > 0)) ok = false;
    const double* yj = &Y[r * ud];
    for (int q = Lp[j] + 1; q < Lp[j] + Lnz[j]; ++q) {
      double* yi = &Y[static_cast<size_t>(slot[static_cast<size_t>(Li[q])]) * ud];
      for (size_t k = 0; k < ud; ++k) yi[k] -= Lx[q] * yj[k];
    }
    for (int a = 0; a < d; ++a)
      for (int b = 0; b <= a; ++b) out(a, b) += yj[a] * yj[b] / dj;
  }
  out.triangularView<Eigen::StrictlyUpper>() = out.transpose();
  for (int j : path) slot[static_cast<size_t>(j)] = -1;
  if (!ok || !out.allFinite()) return {};
  return symmetrized(out);
}

}  // namespace sextant::graph::smoother
