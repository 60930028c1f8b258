// libFuzzer target: the scene loader on arbitrary bytes. A scene is either loaded (and then it
// must survive the round trip through JSON unchanged) or rejected with a SceneError; anything
// else — another exception, a crash, a sanitizer report — is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "physbench/scene_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  physbench::Scene scene;
  try {
    scene = physbench::load_scene_text(text, "fuzz.json");
  } catch (const physbench::SceneError&) {
    return 0;
  }
  // what the loader accepts it must also write and read back as the same scene
  const nlohmann::json once = physbench::to_json(scene);
  const physbench::Scene back = physbench::load_scene_text(once.dump(), "fuzz.json (written back)");
  if (physbench::to_json(back) != once) __builtin_trap();
  return 0;
}
