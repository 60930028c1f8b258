// A scene as an rtp world: the one place that maps the scene's bodies and springs onto rtp, used
// by the rtp adapter and by the contact benchmark, so both step the same world.
#pragma once

#include <rtp/world.h>

#include "physbench/scene.h"

namespace physbench {

// Bodies get their shapes only where the scene has contacts (Scene::has_contacts): a scene
// without them keeps the integrator; particles are not part of the world.
rtp::World make_rtp_world(const Scene& scene, rtp::Integrator integrator,
                          const rtp::ContactSettings& contacts);

}  // namespace physbench
