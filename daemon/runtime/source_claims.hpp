#pragma once
// One identity, one sender: the first sender (the `sender` every sextant message carries) heard on a stream (a body's
// odometry, sightings or loops, a passive sensor's scans) holds it; another sender's messages on that stream are
// refused ("source_claimed") while the holder is active.  Hand-over: when the holder has been silent for
// `handover_s` of data time (the messages' utime, so that replay decides as the daemon did), the next sender to
// speak holds the stream.  Two robots configured with the same name, or a spoofer, then never interleave their
// poses in one estimate; a restarted driver (a new sender name) takes over after handover_s.
// Memory: at most `max_streams` claims; a new stream beyond them takes the place of the claim silent longest.
#include <cstdint>
#include <map>
#include <string>

namespace sextant::runtime {

class SourceClaims {
 public:
  SourceClaims(double handover_s, size_t max_streams);

  /// Whether `sender` may speak for `stream` with a message stamped `utime`; records the claim when it may.
  bool claim(const std::string& stream, const std::string& sender, int64_t utime);
  /// Messages refused so far.
  int64_t refused() const { return refused_; }
  void forget(const std::string& stream) { holders_.erase(stream); }

 private:
  struct Holder {
    std::string sender;
    int64_t last_utime = 0;
  };
  int64_t handover_us_;
  size_t max_streams_;
  std::map<std::string, Holder> holders_;
  int64_t refused_ = 0;
};

}  // namespace sextant::runtime
