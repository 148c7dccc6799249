#pragma once
// Picture sizes given on the command line as WxH.
#include <string>
#include <utility>

namespace floesim::viz {
// "1280x720" -> {1280, 720}; InputError naming `option` unless both are whole
// numbers in [64, 8192].
std::pair<int, int> parse_size(const std::string& text, const std::string& option);
}  // namespace floesim::viz
