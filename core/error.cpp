#include "core/error.hpp"

namespace floesim {

std::string where(const std::string& file, long line, const std::string& key,
                  const std::string& message) {
  std::string s;
  if (!file.empty()) {
    s += file;
    if (line > 0) s += ":" + std::to_string(line);
    s += ": ";
  }
  if (!key.empty()) s += "key '" + key + "': ";
  return s + message;
}

}  // namespace floesim
