// MuJoCo 2.2.2's contact buffers, sized from a contact scene (adapters/src/mujoco_adapter.cpp).
#pragma once

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

}  // namespace physbench
