// Assembly of the incremental smoother's normal equations H = sum_f J_f' W_f J_f, g = sum_f J_f' W_f e_f
// (W_f = w_f Omega_f, w_f the robust weight at the linearization point), block by block straight into CHOLMOD's
// compressed columns (upper triangle, by column position).
#include "estimators/graph/smoother/linear_system.hpp"
#include "estimators/graph/smoother/smoother_state.hpp"

#include <algorithm>

namespace sextant::graph::smoother {

// The pattern is known from which variables share a factor, so there is no triplet list to sort and sum (on
// city10000 that conversion alone took as long as linearizing).  Reserved columns hold an identity.
bool assemble_pattern(SmootherState& s, System& sys) {
  const auto& vars = s.graph.variables();
  const auto& factors = s.graph.factors();
  const size_t nv = vars.size();
  sys.first.assign(nv + 1, 0);
  sys.count.assign(nv, 0);
  auto each_pair = [&](auto&& visit) {
    for (size_t f : sys.factors)
      for (int a : factors[f]->variables())
        for (int b : factors[f]->variables())
          if (sys.pos[static_cast<size_t>(a)] >= 0 && sys.pos[static_cast<size_t>(a)] < sys.pos[static_cast<size_t>(b)])
            visit(a, b);
  };
  each_pair([&](int, int b) { ++sys.first[static_cast<size_t>(b) + 1]; });
  for (size_t v = 0; v < nv; ++v) sys.first[v + 1] += sys.first[v];
  sys.before.assign(static_cast<size_t>(sys.first[nv]), 0);
  each_pair([&](int a, int b) {
    sys.before[static_cast<size_t>(sys.first[static_cast<size_t>(b)] + sys.count[static_cast<size_t>(b)]++)] = a;
  });
  size_t nnz = static_cast<size_t>(sys.reserve_end - sys.used);
  for (size_t v = 0; v < nv; ++v) {
    int* r = sys.before.data() + sys.first[v];
    std::sort(r, r + sys.count[v],
              [&](int a, int b) { return sys.pos[static_cast<size_t>(a)] < sys.pos[static_cast<size_t>(b)]; });
    sys.count[v] = static_cast<int>(std::unique(r, r + sys.count[v]) - r);
    if (sys.pos[v] < 0) continue;
    size_t above = 0;
    for (int k = 0; k < sys.count[v]; ++k) above += static_cast<size_t>(vars[static_cast<size_t>(r[k])].dim());
    const size_t d = static_cast<size_t>(vars[v].dim());
    nnz += d * above + d * (d + 1) / 2;
  }
  sys.H = own(cholmod_allocate_sparse(static_cast<size_t>(sys.capacity), static_cast<size_t>(sys.capacity), nnz, 1, 1,
                                      1, CHOLMOD_REAL, s.workspace.get()),
              s.workspace);
  if (sys.H == nullptr) return false;
  int* Hp = static_cast<int*>(sys.H->p);
  int* Hi = static_cast<int*>(sys.H->i);
  double* Hx = static_cast<double*>(sys.H->x);
  std::fill(Hx, Hx + nnz, 0.0);
  size_t at = 0;
  for (int c = 0; c < sys.capacity; ++c) {
    Hp[c] = static_cast<int>(at);
    if (c >= sys.used && c < sys.reserve_end) {
      Hi[at] = c, Hx[at] = 1.0, ++at;
      continue;
    }
    const size_t v = static_cast<size_t>(sys.col_var[static_cast<size_t>(c)]);  // a variable's columns are filled
    const int d = vars[v].dim();                                                // together, at its first one
    for (int k = 0; k < d; ++k) {
      Hp[c + k] = static_cast<int>(at);
      for (int j = sys.first[v]; j < sys.first[v] + sys.count[v]; ++j) {
        const size_t u = static_cast<size_t>(sys.before[static_cast<size_t>(j)]);
        for (int i = 0; i < vars[u].dim(); ++i) Hi[at++] = sys.pos[u] + i;
      }
      for (int i = 0; i <= k; ++i) Hi[at++] = c + i;
    }
    c += d - 1;
  }
  Hp[sys.capacity] = static_cast<int>(at);
  sys.g = Eigen::VectorXd::Zero(sys.capacity);
  return true;
}

void assemble_values(const SmootherState& s, System& sys, size_t end) {
  const auto& vars = s.graph.variables();
  const auto& factors = s.graph.factors();
  const int* Hp = static_cast<const int*>(sys.H->p);
  double* Hx = static_cast<double*>(sys.H->x);
  // Block (a, b), pos a <= pos b, of a factor: J_a' W J_b added at a's rows in b's columns.
  auto offset_in_column = [&](int a, int b) {
    int off = 0;
    for (int j = sys.first[static_cast<size_t>(b)];
         j < sys.first[static_cast<size_t>(b)] + sys.count[static_cast<size_t>(b)]; ++j) {
      const int u = sys.before[static_cast<size_t>(j)];
      if (u == a) return off;
      off += vars[static_cast<size_t>(u)].dim();
    }
    return off;  // a == b: its own block follows all the others
  };
  // Buffers reused from factor to factor (the linearization while the shapes repeat): a rebuild linearizes every
  // factor, and per-factor allocations were a third of its assembly time.
  Linearization lin;
  Eigen::VectorXd We;
  Eigen::MatrixXd JaW, block;
  for (; sys.assembled < end; ++sys.assembled) {
    const size_t f = sys.factors[sys.assembled];
    const Factor& fac = *factors[f];
    const auto& fv = fac.variables();
    fac.shape(lin, sys.lin);
    fac.linearize(sys.lin, lin);
    const double w = s.kernel_weight(f, fac.weighted_square(lin.error, We));  // leaves We = Omega e
    We *= w;
    for (size_t ka = 0; ka < fv.size(); ++ka) {
      const int pa = sys.pos[static_cast<size_t>(fv[ka])];
      if (pa < 0) continue;
      const Eigen::MatrixXd& Ja = lin.jacobians[ka];
      sys.g.segment(pa, Ja.cols()).noalias() += Ja.transpose() * We;
      JaW.noalias() = w * (Ja.transpose() * fac.information());
      for (size_t kb = 0; kb < fv.size(); ++kb) {
        const int pb = sys.pos[static_cast<size_t>(fv[kb])];
        if (pb < pa) continue;
        block.noalias() = JaW * lin.jacobians[kb];
        const int off = offset_in_column(fv[ka], fv[kb]);
        for (int k = 0; k < block.cols(); ++k) {
          double* col = Hx + Hp[pb + k] + off;
          const int rows = pa == pb ? k + 1 : static_cast<int>(block.rows());
          for (int i = 0; i < rows; ++i) col[i] += block(i, k);
        }
      }
    }
  }
}

}  // namespace sextant::graph::smoother
