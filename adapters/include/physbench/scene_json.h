// Scene <-> JSON, with the same meaning as the C++ structure (docs/scene-format.md).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "physbench/scene.h"

namespace physbench {

nlohmann::json to_json(const Scene& scene);

// Parses and validates. Errors name the source and field: "scenes/x.json: bodies[0].mass: ..."
Scene scene_from_json(const nlohmann::json& document, const std::string& source = "scene");
// The text of a scene file: duplicate keys, numbers past a double, nesting and size are named too.
Scene load_scene_text(std::string_view text, const std::string& source);
Scene load_scene_file(const std::string& path);
void save_scene_file(const Scene& scene, const std::string& path);

}  // namespace physbench
