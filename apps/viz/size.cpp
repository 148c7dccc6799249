#include "apps/viz/size.hpp"

#include <cstdio>

#include "core/error.hpp"

namespace floesim::viz {

std::pair<int, int> parse_size(const std::string& text, const std::string& option) {
  int w = 0, h = 0;
  char end = 0;
  const int got = std::sscanf(text.c_str(), "%dx%d%c", &w, &h, &end);
  if (got != 2 || w < 64 || h < 64 || w > 8192 || h > 8192)
    throw InputError(option + ": '" + text + "' is not a picture size: expected WxH with each between 64 and 8192 "
                     "pixels, e.g. 1280x720");
  return {w, h};
}

}  // namespace floesim::viz
