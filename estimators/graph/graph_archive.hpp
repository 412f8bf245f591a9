#pragma once
// Variables and factors in the binary archive (estimators/archive/binary_archive.hpp), for saving a graph and
// building it again (the daemon's state directory).  A factor is saved as its type tag, its variable indices, its
// information and its measurement; restoring gives a factor whose residual, Jacobians and chi2 are bit for bit the
// saved one's.  The factor types the daemon builds are supported (RelativePoseFactor planar and 3-D,
// PointObservationFactor); any other type throws std::invalid_argument when saved, naming it.
#include "estimators/archive/binary_archive.hpp"
#include "estimators/graph/factor.hpp"
#include "estimators/graph/variable.hpp"

#include <memory>

namespace sextant::graph {

void save(archive::ArchiveWriter& w, const Variable& v);
void load(archive::ArchiveReader& r, Variable& v);

void save_factor(archive::ArchiveWriter& w, const Factor& f);
/// Throws archive::ArchiveError for an unknown tag or a malformed factor (sizes that do not match its model).
std::unique_ptr<Factor> load_factor(archive::ArchiveReader& r);

}  // namespace sextant::graph
