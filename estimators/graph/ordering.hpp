#pragma once
// Fill-reducing orderings of the sparse normal equations (sparse_normal_equations.hpp, the smoother's linear system).
//   kBlockAmd  AMD (Amestoy, Davis, Duff 1996) on the variable (block) graph, expanded to the scalar columns: every
//              variable's components stay together and the supernodes align with the blocks (as Ceres does);
//   kAmd, kColamd, kMetis  CHOLMOD's orderings of the scalar matrix (COLAMD: Davis et al. 2004; METIS nested
//              dissection: Karypis and Kumar 1998);
//   kAuto      CHOLMOD's own choice among those it tries.

namespace sextant::graph {

enum class Ordering { kBlockAmd, kAmd, kColamd, kMetis, kAuto };

}  // namespace sextant::graph
