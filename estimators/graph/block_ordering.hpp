#pragma once
// Fill-reducing orderings of the block (variable) graph of the normal equations, expanded to scalar unknowns: every
// variable's components stay together and consecutive, so the factor's supernodes align with the variables (as
// Ceres orders its Schur/Cholesky systems).  AMD: Amestoy, Davis and Duff, SIMAX 1996; the constrained variant (CAMD)
// orders each constraint group after the previous one — used to put the newest variables last, so that the next
// incremental updates touch only the end of the factor (iSAM's ordering heuristic, Kaess et al. 2008 sec. V).
// Nested dissection (METIS, Karypis and Kumar, SISC 1998, through CHOLMOD) costs more to compute but finds less fill
// on large planar-like graphs: on city10000 it halves the factorization flops of AMD.
#include <cholmod.h>

#include <vector>

namespace sextant::graph {

/// `upper_rows[b]`: the blocks a <= b coupled to block b (b itself included), sorted ascending.
/// `group` (optional, size = number of blocks): constraint group of each block; groups are ordered ascending.
/// Returns the order: position -> block.  Throws std::runtime_error when CHOLMOD fails.
std::vector<int> block_amd_order(const std::vector<std::vector<int>>& upper_rows, cholmod_common& common,
                                 const std::vector<int>* group = nullptr);
/// The same input and result, by METIS nested dissection.
std::vector<int> block_nested_dissection_order(const std::vector<std::vector<int>>& upper_rows, cholmod_common& common);

}  // namespace sextant::graph
