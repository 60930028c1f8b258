// Small text helpers the runner's stages share: numbers as results.csv writes them, file names.
#pragma once

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

namespace physbench {

// the median of the values (NaN for none)
inline double median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// a message's parts, joined by "; "
inline void append(std::string& message, const std::string& more) {
  message += (message.empty() ? "" : "; ") + more;
}

// 9 significant digits; NaN (a value that could not be computed) is empty
inline std::string number(double value) {
  if (!std::isfinite(value)) return std::isnan(value) ? "" : (value > 0 ? "inf" : "-inf");
  std::ostringstream out;
  out << std::setprecision(9) << value;
  return out.str();
}

// every bit of a double, for values that are matched rather than read
inline std::string exact(double value) {
  std::ostringstream out;
  out << std::setprecision(17) << value;
  return out.str();
}

// 64-bit FNV-1a of a text, in hex: the plan's fingerprint (the same text gives the same value on
// every machine, which std::hash does not promise)
inline std::string fingerprint(const std::string& text) {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  for (unsigned char c : text) hash = (hash ^ c) * 0x100000001b3ull;
  std::ostringstream out;
  out << std::hex << std::setw(16) << std::setfill('0') << hash;
  return out.str();
}

// a name as a file name: anything but letters, digits, '-' and '.' becomes '_'
inline std::string safe_name(std::string s) {
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '.') c = '_';
  return s;
}

}  // namespace physbench
