// Bullet's version as the adapters report it: "3.24 (float)". Included only by sources that
// link Bullet.
#pragma once

#include <LinearMath/btScalar.h>

#include <string>

namespace physbench {

inline std::string bullet_version(const std::string& precision) {
  const int v = btGetVersion();
  return std::to_string(v / 100) + "." + std::to_string(v % 100) + " (" + precision + ")";
}

}  // namespace physbench
