#pragma once
// Raw (undecoded) LCM subscriptions through LCM's C API.  LCM 1.3.1's C++ wrapper for method subscriptions hands
// its callback a pointer that UndefinedBehaviorSanitizer rejects (and that crashes under ASan+UBSan builds), so
// sextant subscribes with the C call and a plain function.
#include <lcm/lcm-cpp.hpp>

#include <string>

namespace sextant::runtime {

/// Calls `handler->on_message(const lcm_recv_buf_t&, const std::string& channel)` for every message on channels
/// matching the regular expression `channel`.  `handler` must outlive the subscription.  Returns the C
/// subscription (for lcm_subscription_set_queue_capacity), or nullptr when LCM is not initialised.
template <class Handler>
lcm_subscription_t* subscribe_raw(lcm::LCM& lcm, const std::string& channel, Handler* handler) {
  if (!lcm.good()) return nullptr;
  return lcm_subscribe(
      lcm.getUnderlyingLCM(), channel.c_str(),
      [](const lcm_recv_buf_t* rbuf, const char* ch, void* user) {
        static_cast<Handler*>(user)->on_message(*rbuf, std::string(ch));
      },
      handler);
}

}  // namespace sextant::runtime
