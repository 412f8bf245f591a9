#include "daemon/runtime/udp_drops.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <system_error>

namespace sextant::runtime {

std::optional<int64_t> udp_receive_drops() {
  // The inodes of this process's sockets: /proc/self/fd/N -> "socket:[INODE]".
  std::set<std::string> inodes;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    std::error_code ec2;
    const std::string target = std::filesystem::read_symlink(e.path(), ec2).string();
    if (!ec2 && target.rfind("socket:[", 0) == 0) inodes.insert(target.substr(8, target.size() - 9));
  }
  if (ec) return std::nullopt;
  bool readable = false;
  int64_t drops = 0;
  for (const char* table : {"/proc/net/udp", "/proc/net/udp6"}) {
    std::ifstream in(table);
    if (!in) continue;
    readable = true;
    std::string line;
    std::getline(in, line);  // header
    // sl local rem st tx:rx tr:when retrnsmt uid timeout inode ref pointer drops
    while (std::getline(in, line)) {
      std::istringstream f(line);
      std::string col[13];
      for (auto& c : col) f >> c;
      if (f && inodes.count(col[9])) drops += std::strtoll(col[12].c_str(), nullptr, 10);
    }
  }
  return readable ? std::optional<int64_t>(drops) : std::nullopt;
}

}  // namespace sextant::runtime
