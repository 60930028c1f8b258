// Small text helpers the runner's stages share: numbers as results.csv writes them, file names.
#pragma once

#include <cctype>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <sstream>
#include <string>

namespace physbench {

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
