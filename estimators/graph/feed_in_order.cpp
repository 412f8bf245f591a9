#include "estimators/graph/feed_in_order.hpp"

#include <chrono>

namespace sextant::graph {

FeedResult feed_in_order(const FactorGraph& graph, IncrementalSmoother& smoother) {
  FeedResult r;
  const auto& vars = graph.variables();
  std::vector<int> to_smoother(vars.size(), -1);
  bool pending = false;
  auto step = [&] {
    const auto t0 = std::chrono::steady_clock::now();
    const IncrementalStatus st = smoother.update();
    r.step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    r.rebuilds += st.rebuilt ? 1 : 0;
    r.relinearized_factors += st.relinearized_factors;
    r.deferred_at_end = st.deferred_variables;
    if (!st.ok && r.ok) r.ok = false, r.message = st.message;
    pending = false;
  };
  for (const auto& f : graph.factors()) {
    const auto& fv = f->variables();
    for (size_t k = 0; k < fv.size(); ++k) {
      const size_t v = static_cast<size_t>(fv[k]);
      if (to_smoother[v] >= 0) continue;
      if (pending && vars[v].is_pose()) {
        step();
        if (!r.ok) return r;
      }
      Variable init = vars[v];
      const auto* rel = dynamic_cast<const RelativePoseFactor*>(f.get());
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
    smoother.add_factor(f->rebind(mapped));
    r.start.add_factor(f->rebind(mapped));
    pending = true;
  }
  if (pending) step();
  return r;
}

}  // namespace sextant::graph
