#include "core/error.hpp"

#include <sstream>

namespace floesim {

std::string where(const std::string& file, long line, const std::string& key,
                  const std::string& message) {
  std::ostringstream s;
  if (!file.empty()) {
    s << file;
    if (line > 0) s << ':' << line;
    s << ": ";
  }
  if (!key.empty()) s << "key '" << key << "': ";
  s << message;
  return s.str();
}

}  // namespace floesim
