// MuJoCo's contact buffers, sized from a contact scene (adapters/src/mujoco_adapter.cpp), and the
// adapter's variants for each MuJoCo version it is built against.
#pragma once

#include <string>
#include <vector>

#include "physbench/scene.h"

namespace physbench {

struct MujocoBuffers {
  long nconmax = 0;  // contacts (0: MuJoCo's default, for scenes without contacts)
  long njmax = 0;    // constraint rows
};

// Room for the contacts of every pair that touches at the start or can meet (bounds within 5 cm,
// grown by the starting speeds over the duration) and of each dynamic body with each plane it is
// that near or that it can fall onto (nothing else is near it), at 4 points a box pair, plus a
// quarter; a contact set that outgrows it overflows, and the adapter reports that as an error
MujocoBuffers mujoco_buffers(const Scene& scene);

// the variants of the adapter built against MuJoCo headers of this mjVERSION_HEADER (222 for
// 2.2.2, 4000000 for 4.0.0): `implicitfast` exists from 2.3.3 on
inline std::vector<std::string> mujoco_variants(long version_header) {
  std::vector<std::string> variants{"euler", "rk4", "implicit"};
  if (version_header >= 233) variants.push_back("implicitfast");
  variants.push_back("pgs-10");
  return variants;
}

}  // namespace physbench
