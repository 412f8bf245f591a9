#include "daemon/runtime/state_directory.hpp"

#include "daemon/runtime/stage_runner.hpp"

#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>

namespace sextant::runtime {

std::string state_file_path(const std::string& dir) { return (std::filesystem::path(dir) / kStateFileName).string(); }

bool restore_stages(const std::string& path, uint64_t fingerprint, const std::vector<engine::Stage*>& stages) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return false;
  const std::vector<StateSection> sections = decode_state(read_whole_file(path), fingerprint, path);
  std::string saved, wanted;
  for (const auto& s : sections) saved += (saved.empty() ? "" : ", ") + s.name;
  for (const auto* s : stages) wanted += (wanted.empty() ? "" : ", ") + std::string(s->name());
  if (saved != wanted)
    throw StateFileError(path + ": saved by a daemon with the stages [" + saved + "], this one runs [" + wanted + "]");
  for (size_t i = 0; i < stages.size(); ++i) {
    const std::string& bytes = sections[i].bytes;
    archive::ArchiveReader r(bytes.data(), bytes.size(), path + " (stage '" + sections[i].name + "')");
    try {
      stages[i]->load(r);
      r.expect_end();
    } catch (const archive::ArchiveError& e) {
      throw StateFileError(e.what());
    } catch (const std::exception& e) {
      throw StateFileError(path + " (stage '" + sections[i].name + "'): " + e.what());
    }
  }
  return true;
}

std::string set_state_file_aside(const std::string& path) {
  const std::string aside = path + ".bad-" + std::to_string(static_cast<long long>(std::time(nullptr)));
  if (std::rename(path.c_str(), aside.c_str()) != 0)
    throw StateFileError(path + ": cannot rename it to " + aside + ": " + std::strerror(errno));
  return aside;
}

StateSave save_stages(const std::string& path, uint64_t fingerprint,
                      const std::vector<std::unique_ptr<StageRunner>>& runners) {
  using Clock = std::chrono::steady_clock;
  StateSave result;
  const auto t0 = Clock::now();
  std::vector<StateSection> sections;
  for (const auto& r : runners)
    r->with_stage([&](engine::Stage& stage) {
      archive::ArchiveWriter w;
      try {
        stage.save(w);
      } catch (const std::exception& e) {
        throw StateFileError("stage '" + std::string(stage.name()) + "' could not save its state: " + e.what());
      }
      sections.push_back({std::string(stage.name()), w.take()});
    });
  const auto t1 = Clock::now();
  const std::string bytes = encode_state(fingerprint, sections);
  write_file_atomically(path, bytes);
  result.bytes = bytes.size();
  result.collect_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  result.write_ms = std::chrono::duration<double, std::milli>(Clock::now() - t1).count();
  return result;
}

}  // namespace sextant::runtime
