#include "estimators/graph/feed_in_order.hpp"

#include <algorithm>
#include <chrono>

namespace sextant::graph {

FeedResult feed_in_order(const FactorGraph& graph, IncrementalSmoother& smoother) {
  FeedResult r;
  const auto& vars = graph.variables();
  // The step of each factor: its latest pose (factors without a pose go with the first step).
  std::vector<std::vector<size_t>> steps(vars.size() + 1);
  for (size_t fi = 0; fi < graph.factors().size(); ++fi) {
    int latest = -1;
    for (int v : graph.factors()[fi]->variables())
      if (vars[static_cast<size_t>(v)].is_pose()) latest = std::max(latest, v);
    steps[static_cast<size_t>(std::max(latest, 0))].push_back(fi);
  }
  std::vector<int> to_smoother(vars.size(), -1);
  for (const auto& step : steps) {
    if (step.empty()) continue;
    for (size_t fi : step) {
      const Factor& f = *graph.factors()[fi];
      const auto& fv = f.variables();
      for (size_t k = 0; k < fv.size(); ++k) {
        const size_t v = static_cast<size_t>(fv[k]);
        if (to_smoother[v] >= 0) continue;
        Variable init = vars[v];
        const auto* rel = dynamic_cast<const RelativePoseFactor*>(&f);
        if (rel != nullptr && !init.fixed) {
          const size_t other = static_cast<size_t>(fv[1 - k]);
          if (to_smoother[other] >= 0) {
            const Variable& known = smoother.graph().variables()[static_cast<size_t>(to_smoother[other])];
            if (rel->planar())
              init.pose2 = k == 1 ? known.pose2 * rel->measurement2() : known.pose2 * rel->measurement2().inverse();
            else
              init.pose3 = k == 1 ? known.pose3 * rel->measurement3() : known.pose3 * rel->measurement3().inverse();
          }
        }
        to_smoother[v] = smoother.add_variable(init);
        r.start.add_variable(init);
      }
      std::vector<int> mapped;
      for (int v : fv) mapped.push_back(to_smoother[static_cast<size_t>(v)]);
      smoother.add_factor(f.rebind(mapped));
      r.start.add_factor(f.rebind(mapped));
    }
    const auto t0 = std::chrono::steady_clock::now();
    const IncrementalStatus st = smoother.update();
    r.step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    r.steps.push_back({st, smoother.factor_nonzeros(), smoother.reordering()});
    r.rebuilds += st.rebuilt ? 1 : 0;
    r.relinearized_factors += st.relinearized_factors;
    r.deferred_at_end = st.deferred_variables;
    if (!st.ok) {
      r.ok = false;
      r.message = st.message;
      return r;
    }
  }
  // The final estimate is the exact solution of the last linearization; its cost is counted in the last step.
  const auto t0 = std::chrono::steady_clock::now();
  smoother.refresh_estimate();
  if (!r.step_ms.empty())
    r.step_ms.back() += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace sextant::graph
