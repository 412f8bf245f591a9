#include "daemon/runtime/input_router.hpp"

namespace sextant::runtime {

bool route_input(Intake& intake, const std::vector<std::unique_ptr<StageRunner>>& runners, ChannelStats& stats,
                 const std::string& channel, const void* data, size_t size,
                 std::chrono::steady_clock::time_point received) {
  auto event = intake.accept(channel, data, size);
  for (const std::string& body : intake.take_expired_bodies())
    for (const auto& r : runners) r->forget(body);
  if (!event) return false;
  const QueuedEvent queued{std::move(*event), received, intake.resynced_body()};
  for (const auto& r : runners)
    if (r->accepts(queued.event) && !r->offer(queued)) stats.dropped(channel);
  return true;
}

}  // namespace sextant::runtime
