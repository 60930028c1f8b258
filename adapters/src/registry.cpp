// The engines linked into this executable; which ones is decided by the build (PHYSBENCH_HAVE_*).
#include "physbench/registry.h"

namespace physbench {

#ifdef PHYSBENCH_RTP_ISA_SUFFIX
namespace {

// rtp's default variants (the contact step and the rigid-body integrator), and the contact step at
// Box2D v3's settings (soft-step-4: Box3D's rules, for a ratio at equal settings and equal
// instruction set), under names that say the instruction set, for physbench-rtp-baseline; every
// call strips the suffix again
EngineInfo with_isa_suffix(EngineInfo rtp, const std::string& suffix) {
  const EngineInfo inner = rtp;
  auto strip = [suffix](const std::string& variant) {
    return variant.ends_with(suffix) ? variant.substr(0, variant.size() - suffix.size()) : variant;
  };
  rtp.variants = {"soft-step" + suffix, "soft-step-4" + suffix, "rk4" + suffix};
  rtp.unsupported = [inner, strip](const Scene& scene, const std::string& variant) {
    return inner.unsupported(scene, strip(variant));
  };
  rtp.create = [inner, strip](const std::string& variant) { return inner.create(strip(variant)); };
  rtp.applies = [inner, strip](const Scene& scene, const std::string& variant) {
    return inner.applies(scene, strip(variant));
  };
  rtp.settings = [inner, strip](const std::string& variant) {
    return inner.settings(strip(variant));
  };
  return rtp;
}

}  // namespace
#endif

const std::vector<EngineInfo>& linked_engines() {
  static const std::vector<EngineInfo> engines = [] {
    std::vector<EngineInfo> list;
#if defined(PHYSBENCH_HAVE_RTP) && defined(PHYSBENCH_RTP_ISA_SUFFIX)
    list.push_back(with_isa_suffix(rtp_engine_info(), PHYSBENCH_RTP_ISA_SUFFIX));
#elif defined(PHYSBENCH_HAVE_RTP)
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
