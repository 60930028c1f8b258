// What the physbench command's end-to-end tests share (test_runner.cpp, test_timing.cpp): a
// fresh folder, the command run with its output kept, and results.csv read back as rows. Each
// test file gets its own copy (an unnamed namespace; inline, so a file need not use them all).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <tuple>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "physbench/process.h"
#include "physbench/registry.h"
#include "physbench/metrics.h"
#include "physbench/runner.h"
#include "physbench/scenarios.h"
#include "physbench/scene_json.h"

// the linked MuJoCo build's name ("mujoco-2.2" where MuJoCo 4, in physbench-mujoco4, is the
// mujoco row)
static const std::string kMujoco = physbench::mujoco_engine_name();

namespace {

namespace fs = std::filesystem;
using physbench::ChildOutcome;
using physbench::run_child;
using physbench::tail_of_file;

struct Invocation {
  ChildOutcome outcome;
  std::string output;  // stdout and stderr together
};

inline fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() /
                       ("physbench_test_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

inline Invocation physbench(const std::vector<std::string>& args, const fs::path& dir) {
  std::vector<std::string> argv = {PHYSBENCH_EXE};
  argv.insert(argv.end(), args.begin(), args.end());
  const fs::path log = dir / "physbench.log";
  Invocation inv;
  inv.outcome = run_child(argv, log.string(), 300.0);
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  inv.output = text.str();
  return inv;
}

// results.csv as rows of column → value
inline std::vector<std::map<std::string, std::string>> read_rows(const fs::path& csv) {
  std::ifstream in(csv);
  std::vector<std::map<std::string, std::string>> rows;
  auto split = [](const std::string& line) {
    std::vector<std::string> fields;
    std::string field;
    bool quoted = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char c = line[i];
      if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"')
        field += '"', ++i;
      else if (c == '"')
        quoted = !quoted;
      else if (c == ',' && !quoted)
        fields.push_back(field), field.clear();
      else
        field += c;
    }
    fields.push_back(field);
    return fields;
  };
  std::string line;
  std::getline(in, line);
  const auto header = split(line);
  while (std::getline(in, line)) {
    const auto fields = split(line);
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < fields.size(); ++i) row[header[i]] = fields[i];
    rows.push_back(row);
  }
  return rows;
}

inline const std::map<std::string, std::string>* find_row(
    const std::vector<std::map<std::string, std::string>>& rows, const std::string& engine,
    const std::string& variant) {
  for (const auto& r : rows)
    if (r.at("engine") == engine && r.at("variant") == variant) return &r;
  return nullptr;
}

}  // namespace
