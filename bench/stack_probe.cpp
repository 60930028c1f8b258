// stack_probe: one contact scenario on rtp with chosen solver settings, and what the stack did —
// the tool behind the solver figures in docs/history.md ("Solver"). Prints, every simulated second (or
// every `every` seconds), the drift and the top box's sideways and height change (stderr), and one
// summary line (stdout): drift as the harness defines it (the largest horizontal displacement of
// any box, over the run so far), the top's height change, the deepest penetration the narrow
// phase saw, the energy change (and the largest it reached: the harness's energy added), ms per
// step, and a fingerprint of the final state (FNV-1a over every body's position, orientation and
// momenta, bit for bit: two builds that print the same fingerprint computed the same run), then
// each stage's ms a step (StepProfile). Not a benchmark: time it only against itself, in turn, on
// one machine (docs/metrics.md).
//
//   build/bench/bench/stack_probe pyramid-100 10
//   build/bench/bench/stack_probe pyramid-50 3 substeps 16 hertz 240
//   build/bench/bench/stack_probe pyramid-100 2 every 0.1     (a line every 0.1 s, not every second)
//   build/bench/bench/stack_probe pyramid-10 20 kick 0.01     (the top box pushed sideways at 1 s)
//
// `kick V` gives the top box a velocity of V m/s along z (across a pyramid's one-box depth) at
// t = 1 s, once the stack has settled, and each progress line then gives the range of the top's
// z over its interval: a sway that a standing stack damps shrinks line by line. `nudge V` gives
// every dynamic body V m/s along x at the start: with V at 1e-9 m/s or so, a run whose results
// differ from the unnudged one at round-off only, so that a rare event can be counted over runs.
// `pad N` puts N static boxes, far below the ground and apart, before the scene's own bodies
// (after its first, the ground), so that those take the body indices they would have after N
// others: the contacts' keys, and so the colours' order, of a scene's part as it runs in a larger
// one (`stack_probe pyramid-10 12 pad 9185` is many-pyramids' swaying pyramid alone).
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "physbench/rtp_world.h"
#include "physbench/scenarios.h"

namespace {

// the settings a run may change, by name
std::map<std::string, std::function<void(rtp::ContactSettings&, double)>> settings_by_name() {
  return {
      {"substeps", [](rtp::ContactSettings& s, double v) { s.substeps = int(v); }},
      {"relax", [](rtp::ContactSettings& s, double v) { s.relax_iterations = int(v); }},
      {"max_relax", [](rtp::ContactSettings& s, double v) { s.max_relax_iterations = int(v); }},
      {"recovery_relax",
       [](rtp::ContactSettings& s, double v) { s.recovery_relax_iterations = int(v); }},
      {"recovery_position",
       [](rtp::ContactSettings& s, double v) { s.recovery_position_iterations = int(v); }},
      {"relax_tolerance", [](rtp::ContactSettings& s, double v) { s.relax_tolerance = v; }},
      {"hertz", [](rtp::ContactSettings& s, double v) { s.contact_hertz = v; }},
      {"zeta", [](rtp::ContactSettings& s, double v) { s.damping_ratio = v; }},
      {"push", [](rtp::ContactSettings& s, double v) { s.max_push_speed = v; }},
      {"threads", [](rtp::ContactSettings& s, double v) { s.threads = int(v); }},
      {"cache", [](rtp::ContactSettings& s, double v) { s.pair_cache_distance = v; }},
      {"margin", [](rtp::ContactSettings& s, double v) { s.bounds_margin = v; }},
      {"reuse", [](rtp::ContactSettings& s, double v) { s.manifold_reuse_distance = v; }},
      {"hold", [](rtp::ContactSettings& s, double v) { s.contact_hold_distance = v; }},
      {"match", [](rtp::ContactSettings& s, double v) { s.match_distance = v; }},
      // (the harness's adapter sets the scenes' 0.1 m/s: docs/scene-format.md)
      {"threshold", [](rtp::ContactSettings& s, double v) { s.restitution_threshold = v; }},
      {"local", [](rtp::ContactSettings& s, double v) { s.local_iterations = int(v); }},
      {"alternate", [](rtp::ContactSettings& s, double v) { s.alternate_order = v != 0.0; }},
  };
}

int usage(const char* why) {
  std::fprintf(stderr, "stack_probe: %s\nusage: stack_probe SCENARIO SECONDS [SETTING VALUE]...\nsettings: every (seconds between progress lines) kick (m/s along z, the top box at 1 s) nudge (m/s along x, every body at the start) pad (static boxes before the scene's bodies)", why);
  for (const auto& [name, _] : settings_by_name()) std::fprintf(stderr, " %s", name.c_str());
  std::fprintf(stderr, "\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || argc % 2 == 0) return usage("wrong number of arguments");
  const physbench::Scenario* scenario = physbench::find_scenario(argv[1]);
  if (!scenario) return usage((std::string("no scenario ") + argv[1]).c_str());
  char* end = nullptr;
  const double seconds = std::strtod(argv[2], &end);
  if (*end || !(seconds > 0.0 && seconds <= 3600.0)) return usage("SECONDS must be in (0, 3600]");
  rtp::ContactSettings settings;
  const auto known = settings_by_name();
  double every = 1.0;  // seconds between the progress lines
  double kick = 0.0;   // m/s along z given to the top box at 1 s
  double nudge = 0.0;  // m/s along x given to every dynamic body at the start
  long pad = 0;        // static boxes put before the scene's bodies (after its first)
  for (int i = 3; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) == "every") {
      every = std::strtod(argv[i + 1], &end);
      if (*end || !(every > 0.0 && every <= seconds)) return usage("every must be in (0, SECONDS]");
      continue;
    }
    if (std::string(argv[i]) == "kick") {
      kick = std::strtod(argv[i + 1], &end);
      if (*end || !(std::abs(kick) <= 10.0)) return usage("kick must be a speed within ±10 m/s");
      if (kick != 0.0 && seconds <= 1.0) return usage("kick comes at 1 s: SECONDS must be over 1");
      continue;
    }
    if (std::string(argv[i]) == "pad") {
      pad = std::strtol(argv[i + 1], &end, 10);
      if (*end || pad < 0 || pad > 1'000'000) return usage("pad must be a count of boxes in [0, 1000000]");
      continue;
    }
    if (std::string(argv[i]) == "nudge") {
      nudge = std::strtod(argv[i + 1], &end);
      if (*end || !(std::abs(nudge) <= 1e-3)) return usage("nudge must be a speed within ±1 mm/s");
      continue;
    }
    const auto setting = known.find(argv[i]);
    if (setting == known.end()) return usage((std::string("unknown setting ") + argv[i]).c_str());
    const double value = std::strtod(argv[i + 1], &end);
    if (*end || !std::isfinite(value)) return usage((std::string("not a number: ") + argv[i + 1]).c_str());
    setting->second(settings, value);
  }
  physbench::Scene scene = scenario->build();
  if (!scene.has_contacts()) return usage("the scenario has no contacts");
  if (pad > 0) {
    // (springs, impulses and a chosen probe name bodies by index, which the boxes would shift)
    if (!scene.springs.empty() || !scene.impulses.empty() || !scene.probe.bodies.empty())
      return usage("pad needs a scenario without springs, impulses or chosen probed bodies");
    std::vector<physbench::BodySpec> boxes(static_cast<std::size_t>(pad));
    for (long i = 0; i < pad; ++i) {
      physbench::BodySpec& b = boxes[std::size_t(i)];
      b.name = "pad" + std::to_string(i);
      b.shape.kind = physbench::ShapeKind::Box;
      b.shape.half_extents = rtp::Vec3::Constant(0.5);
      b.mass = 0.0;
      b.position = rtp::Vec3(-500.0 + 3.0 * double(i % 300), -50.0, -500.0 + 3.0 * double(i / 300));
    }
    scene.bodies.insert(scene.bodies.begin() + std::min<std::ptrdiff_t>(1, std::ptrdiff_t(scene.bodies.size())),
                        boxes.begin(), boxes.end());
  }
  rtp::World world = physbench::make_rtp_world(scene, rtp::Integrator::SemiImplicitEuler, settings);
  const int n = int(world.body_count());
  std::vector<rtp::Vec3> start(n);
  int top = -1;
  for (int i = 0; i < n; ++i) {
    start[i] = world.state(i).position;
    if (world.mass(i) > 0.0 && (top < 0 || start[i].y() > start[top].y())) top = i;
  }
  if (top < 0) return usage("the scenario has no dynamic body");
  const double energy = world.mechanical_energy();
  const int steps = int(std::lround(seconds / scene.dt));
  const int per_line = std::max(1, int(std::lround(every / scene.dt)));
  double drift = 0.0, seconds_stepping = 0.0, deepest = 0.0, energy_added_max = 0.0;
  std::size_t relax_passes = 0, touching = 0, moved = 0, held = 0;
  std::size_t line_relax_passes = 0;  // since the last progress line
  std::size_t line_team_steps = 0;  // steps on more than one thread since then (the governor)
  std::size_t line_held = 0, line_touching = 0;  // contacts held, and all, since then
  std::array<double, rtp::StepProfile::kStageNames.size()> stage_seconds{};
  if (nudge != 0.0)
    for (int i = 0; i < n; ++i)
      if (world.mass(i) > 0.0)
        world.apply_impulse(i, rtp::Vec3(nudge * world.mass(i), 0.0, 0.0), world.state(i).position);
  const int kick_step = int(std::lround(1.0 / scene.dt));
  double sway_low = 0.0, sway_high = 0.0;  // the top's z less its start, over the line's interval
  for (int k = 0; k < steps; ++k) {
    if (kick != 0.0 && k == kick_step)
      world.apply_impulse(top, rtp::Vec3(0.0, 0.0, kick * world.mass(top)),
                          world.state(top).position);
    world.step(scene.dt);
    const double sway = world.state(top).position.z() - start[top].z();
    sway_low = (k % per_line == 0) ? sway : std::min(sway_low, sway);
    sway_high = (k % per_line == 0) ? sway : std::max(sway_high, sway);
    seconds_stepping += world.profile().total;
    relax_passes += world.profile().relax_passes;
    line_relax_passes += world.profile().relax_passes;
    line_team_steps += world.profile().threads > 1;
    line_held += world.profile().held_contacts;
    line_touching += world.profile().contact_pairs;
    const auto stages = world.profile().stage_seconds();
    for (std::size_t i = 0; i < stages.size(); ++i) stage_seconds[i] += stages[i];
    touching += world.profile().contact_pairs;
    moved += world.profile().reused_manifolds;
    held += world.profile().held_contacts;
    deepest = std::max(deepest, world.deepest_penetration());
    energy_added_max = std::max(energy_added_max, world.mechanical_energy() - energy);
    for (int i = 0; i < n; ++i) {
      if (world.mass(i) == 0.0) continue;
      const rtp::Vec3 d = world.state(i).position - start[i];
      drift = std::max(drift, std::hypot(d.x(), d.z()));
    }
    if ((k + 1) % per_line == 0) {
      std::fprintf(stderr,
                   "t = %.2f s  drift %.4f m  top x %+.4f m, height %+.4f m  deepest %.4f m  "
                   "%.1f relax passes a step  %.0f %% of steps on the team  %.0f %% of contacts held"
                   "  top z %+.5f..%+.5f m\n",
                   (k + 1) * scene.dt, drift, world.state(top).position.x() - start[top].x(),
                   world.state(top).position.y() - start[top].y(), world.deepest_penetration(),
                   double(line_relax_passes) / per_line, 100.0 * double(line_team_steps) / per_line,
                   line_touching > 0 ? 100.0 * double(line_held) / double(line_touching) : 0.0,
                   sway_low, sway_high);
      line_relax_passes = 0;
      line_team_steps = 0;
      line_held = line_touching = 0;
    }
  }
  std::uint64_t fingerprint = 0xcbf29ce484222325u;  // FNV-1a, 64 bits
  auto hash = [&](double x) {
    unsigned char bytes[sizeof x];
    std::memcpy(bytes, &x, sizeof x);
    for (unsigned char b : bytes) fingerprint = (fingerprint ^ b) * 0x100000001b3u;
  };
  for (int i = 0; i < n; ++i) {
    const rtp::BodyState& s = world.state(i);
    for (int k = 0; k < 3; ++k) hash(s.position[k]), hash(s.linear_momentum[k]);
    for (int k = 0; k < 3; ++k) hash(s.angular_momentum[k]);
    hash(s.orientation.w()), hash(s.orientation.x()), hash(s.orientation.y()), hash(s.orientation.z());
  }
  std::printf("%s %.3g s: drift %.4f m, top %+.4f m, deepest penetration %.4f m, energy %+.3f J "
              "(at most %+.3f), %.4f ms a step, %.2f relax passes a step, state %016llx\n",
              argv[1], seconds, drift, world.state(top).position.y() - start[top].y(), deepest,
              world.mechanical_energy() - energy, energy_added_max, 1e3 * seconds_stepping / steps,
              double(relax_passes) / steps, static_cast<unsigned long long>(fingerprint));
  std::printf("  ms a step by stage:");
  for (std::size_t i = 0; i < stage_seconds.size(); ++i)
    if (stage_seconds[i] > 0.0)
      std::printf(" %s %.4f", rtp::StepProfile::kStageNames[i], 1e3 * stage_seconds[i] / steps);
  std::printf("\n");
  if (moved > 0)
    std::printf("  manifolds moved, not computed: %.1f %% of the touching pairs\n",
                100.0 * double(moved) / double(touching));
  if (held > 0)
    std::printf("  contacts held in last step's blocks: %.1f %% of the touching pairs\n",
                100.0 * double(held) / double(touching));
  return 0;
}
