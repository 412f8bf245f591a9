#pragma once
// Raw (undecoded) LCM subscriptions through LCM's C API.  LCM 1.3.1's C++ wrapper for method subscriptions hands
// its callback a pointer that UndefinedBehaviorSanitizer rejects (and that crashes under ASan+UBSan builds), so
// sextant subscribes with the C call and a plain function.
#include <lcm/lcm-cpp.hpp>

#include <string>

namespace sextant::runtime {

/// Messages LCM holds for a subscription while its handler is busy; beyond, LCM drops them without a trace.  LCM's
/// own default is 30, which a log player's burst or a daemon's trajectory snapshot overflows on a loaded machine.
inline constexpr int kDefaultLcmQueue = 8192;

/// Calls `handler->on_message(const lcm_recv_buf_t&, const std::string& channel)` for every message on channels
/// matching the regular expression `channel`, holding at most `queue_capacity` of them while the handler is busy.
/// `handler` must outlive the subscription.  Returns the C subscription, or nullptr when LCM is not initialised.
template <class Handler>
lcm_subscription_t* subscribe_raw(lcm::LCM& lcm, const std::string& channel, Handler* handler,
                                  int queue_capacity = kDefaultLcmQueue) {
  if (!lcm.good()) return nullptr;
  lcm_subscription_t* s = lcm_subscribe(
      lcm.getUnderlyingLCM(), channel.c_str(),
      [](const lcm_recv_buf_t* rbuf, const char* ch, void* user) {
        static_cast<Handler*>(user)->on_message(*rbuf, std::string(ch));
      },
      handler);
  if (s != nullptr) lcm_subscription_set_queue_capacity(s, queue_capacity);
  return s;
}

}  // namespace sextant::runtime
