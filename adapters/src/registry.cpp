// The engines linked into this executable; which ones is decided by the build (PHYSBENCH_HAVE_*).
#include "physbench/registry.h"

namespace physbench {

const std::vector<EngineInfo>& linked_engines() {
  static const std::vector<EngineInfo> engines = [] {
    std::vector<EngineInfo> list;
#ifdef PHYSBENCH_HAVE_RTP
    list.push_back(rtp_engine_info());
#endif
#ifdef PHYSBENCH_HAVE_BULLET
    list.push_back(bullet_engine_info());
#endif
#ifdef PHYSBENCH_HAVE_ODE
    list.push_back(ode_engine_info());
#endif
#ifdef PHYSBENCH_HAVE_BOX2D
    list.push_back(box2d_engine_info());
#endif
#ifdef PHYSBENCH_HAVE_MUJOCO
    list.push_back(mujoco_engine_info());
#endif
#ifdef PHYSBENCH_HAVE_TEST_FAULT
    list.push_back(fault_engine_info());
#endif
    return list;
  }();
  return engines;
}

const EngineInfo* find_linked_engine(const std::string& name) {
  for (const EngineInfo& info : linked_engines())
    if (info.name == name) return &info;
  return nullptr;
}

}  // namespace physbench
