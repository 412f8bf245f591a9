// The config spellings of the engine's kinds (engine_config.hpp, filter_stage_config.hpp,
// association_stage_config.hpp): each kind's names in one table, parsed once where the config is read, so a misspelt
// name is an error, never a default.
#include "daemon/engine/association_stage_config.hpp"
#include "daemon/engine/engine_config.hpp"
#include "daemon/engine/filter_stage_config.hpp"

#include <stdexcept>
#include <string>
#include <utility>

namespace sextant::engine {
namespace {

template <class Kind, size_t N>
Kind from_name(const std::pair<Kind, const char*> (&names)[N], const std::string& name, const char* what) {
  std::string list;
  for (size_t i = 0; i < N; ++i) {
    if (name == names[i].second) return names[i].first;
    list += std::string(i == 0 ? "" : i + 1 == N ? " or " : ", ") + names[i].second;
  }
  throw std::invalid_argument("unknown " + std::string(what) + " '" + name + "' (" + list + ")");
}

template <class Kind, size_t N>
const char* name_of(const std::pair<Kind, const char*> (&names)[N], Kind kind) {
  for (const auto& [k, n] : names)
    if (k == kind) return n;
  return "?";
}

constexpr std::pair<PrimaryEstimator, const char*> kPrimaryEstimators[] = {
    {PrimaryEstimator::kAuto, "auto"}, {PrimaryEstimator::kDeadReckoning, "dead_reckoning"},
    {PrimaryEstimator::kEkf, "ekf"}, {PrimaryEstimator::kPf, "pf"}, {PrimaryEstimator::kGraph, "graph"}};
constexpr std::pair<FilterType, const char*> kFilterTypes[] = {
    {FilterType::kEkf, "ekf"}, {FilterType::kPf, "pf"}, {FilterType::kNone, "none"}};
constexpr std::pair<AssociationSolver, const char*> kAssociationSolvers[] = {
    {AssociationSolver::kLagrangian, "lr"}, {AssociationSolver::kExact, "exact"}};

}  // namespace

PrimaryEstimator primary_estimator_from_name(const std::string& name) {
  return from_name(kPrimaryEstimators, name, "estimator");
}
const char* primary_estimator_name(PrimaryEstimator estimator) { return name_of(kPrimaryEstimators, estimator); }

FilterType filter_type_from_name(const std::string& name) { return from_name(kFilterTypes, name, "filter type"); }
const char* filter_type_name(FilterType type) { return name_of(kFilterTypes, type); }

AssociationSolver association_solver_from_name(const std::string& name) {
  return from_name(kAssociationSolvers, name, "association solver");
}
const char* association_solver_name(AssociationSolver solver) { return name_of(kAssociationSolvers, solver); }

}  // namespace sextant::engine
