// The engines compiled into this executable.
#pragma once

#include <string>
#include <vector>

#include "physbench/engine.h"

namespace physbench {

// every engine adapter linked into this binary, rtp first
const std::vector<EngineInfo>& linked_engines();

// the engine named, or nullptr
const EngineInfo* find_linked_engine(const std::string& name);

// the info function each adapter defines
EngineInfo rtp_engine_info();
EngineInfo bullet_engine_info();
EngineInfo ode_engine_info();
EngineInfo box2d_engine_info();
EngineInfo mujoco_engine_info();
// the engine name of the MuJoCo build linked here: "mujoco", or "mujoco-2.2" for Debian's 2.2.2
// when MuJoCo 4 is the mujoco row (in physbench-mujoco4)
const char* mujoco_engine_name();
// test only: an "engine" whose variants abort or hang in their first step (fault_adapter.cpp)
EngineInfo fault_engine_info();

}  // namespace physbench
