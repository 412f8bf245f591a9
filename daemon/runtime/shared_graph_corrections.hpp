#pragma once
// The daemon's map -> odometry correction board (engine/graph_correction.hpp): the graph stage's thread writes it
// after each optimization, the graph pose stage's thread reads it for every odometry message.  A mutex held only to
// copy one entry in or out, so a reader never waits for a solve.
#include "daemon/engine/graph_correction.hpp"

#include <mutex>

namespace sextant::runtime {

class SharedGraphCorrections final : public engine::GraphCorrectionBoard {
 public:
  void set(const std::string& source, const engine::GraphCorrection& c) override {
    std::lock_guard lock(mutex_);
    board_.set(source, c);
  }
  void erase(const std::string& source) override {
    std::lock_guard lock(mutex_);
    board_.erase(source);
  }
  std::optional<engine::GraphCorrection> get(const std::string& source) const override {
    std::lock_guard lock(mutex_);
    return board_.get(source);
  }

 private:
  mutable std::mutex mutex_;
  engine::GraphCorrections board_;
};

}  // namespace sextant::runtime
