// The spellings of the engine's kinds (stage_kinds.hpp, filter_stage_config.hpp, association_stage_config.hpp): each
// kind's names in one table, parsed once where the config is read, so a misspelt name is an error, never a default.
#include "daemon/engine/stage_kinds.hpp"

#include "daemon/engine/association_stage_config.hpp"
#include "daemon/engine/filter_stage_config.hpp"
#include "estimators/kind_names.hpp"

#include <stdexcept>
#include <string>
#include <utility>

namespace sextant::engine {
namespace {

constexpr std::pair<PrimaryEstimator, const char*> kPrimaryEstimators[] = {
    {PrimaryEstimator::kAuto, "auto"},
    {PrimaryEstimator::kDeadReckoning, "dead_reckoning"},
    {PrimaryEstimator::kEkf, "ekf"},
    {PrimaryEstimator::kPf, "pf"},
    {PrimaryEstimator::kGraph, "graph"},
    {PrimaryEstimator::kInertial, "inertial"},
    {PrimaryEstimator::kInertialGraph, "inertial_graph"}};
constexpr std::pair<FilterType, const char*> kFilterTypes[] = {
    {FilterType::kEkf, "ekf"}, {FilterType::kPf, "pf"}, {FilterType::kNone, "none"}};
constexpr std::pair<AssociationSolver, const char*> kAssociationSolvers[] = {{AssociationSolver::kLagrangian, "lr"},
                                                                             {AssociationSolver::kExact, "exact"}};
constexpr std::pair<StageKind, const char*> kStageKinds[] = {{StageKind::kDeadReckoning, "dead_reckoning"},
                                                             {StageKind::kFilter, "filter"},
                                                             {StageKind::kParticleFilter, "particle_filter"},
                                                             {StageKind::kGraph, "graph"},
                                                             {StageKind::kGraphPose, "graph_pose"},
                                                             {StageKind::kAssociation, "association"},
                                                             {StageKind::kInertial, "inertial"},
                                                             {StageKind::kInertialGraph, "inertial_graph"},
                                                             {StageKind::kOther, "other"}};

}  // namespace

PrimaryEstimator primary_estimator_from_name(const std::string& name) {
  return kind_from_name(kPrimaryEstimators, name, "estimator");
}
const char* primary_estimator_name(PrimaryEstimator estimator) { return kind_name(kPrimaryEstimators, estimator); }

FilterType filter_type_from_name(const std::string& name) { return kind_from_name(kFilterTypes, name, "filter type"); }
const char* filter_type_name(FilterType type) { return kind_name(kFilterTypes, type); }

AssociationSolver association_solver_from_name(const std::string& name) {
  return kind_from_name(kAssociationSolvers, name, "association solver");
}
const char* association_solver_name(AssociationSolver solver) { return kind_name(kAssociationSolvers, solver); }

const char* stage_kind_name(StageKind kind) { return kind_name(kStageKinds, kind); }

}  // namespace sextant::engine
