// Status honesty: an engine that resets, clamps or drops state on its own, or whose state runs
// away, gives an `exploded` or `error` result with the reason — never `ok`. Each engine is made to
// fail the way it fails, and the status is checked.
#include <gtest/gtest.h>

#include "physbench/scenarios.h"
#include "support.h"
#include "physbench/registry.h"

// the linked MuJoCo build's name ("mujoco-2.2" where MuJoCo 4, in physbench-mujoco4, is the
// mujoco row)
static const std::string kMujoco = physbench::mujoco_engine_name();

namespace {

using namespace physbench;
using physbench::testing::engine;

// k = 10^6 N/m at dt = 1/120: ω dt ≈ 8.3, past every explicit integrator's stability limit
Scene stiff_spring() {
  Scene scene = stiff_spring_scene(1e6);
  scene.dt = 1.0 / 120.0;
  return scene;
}

RunResult run(const std::string& name, const std::string& variant, const Scene& scene) {
  SimulateOptions options;
  options.timing_budget = 0.0;
  return simulate(engine(name), variant, scene, options);
}

TEST(Status, RtpStiffSpringExplodes) {
  for (const char* variant : {"euler", "symplectic", "rk4"}) {
    const RunResult r = run("rtp", variant, stiff_spring());
    EXPECT_EQ(r.status, Status::Exploded) << variant << ": " << r.message;
    EXPECT_NE(r.message.find("non-finite or runaway state"), std::string::npos) << r.message;
  }
}

#ifdef PHYSBENCH_HAVE_BULLET
TEST(Status, BulletStiffSpringExplodes) {
  const RunResult r = run("bullet", "float", stiff_spring());
  EXPECT_EQ(r.status, Status::Exploded) << r.message;
}
#endif

#ifdef PHYSBENCH_HAVE_ODE
TEST(Status, OdeStiffSpringExplodes) {
  const RunResult r = run("ode", "step", stiff_spring());
  EXPECT_EQ(r.status, Status::Exploded) << r.message;
}
#endif

#ifdef PHYSBENCH_HAVE_MUJOCO
// MuJoCo resets the state to the model's initial one after its bad-acceleration warning and
// carries on: the samples stay finite and near the start, and the row used to read `ok`
TEST(Status, MujocoResetAfterBadAccelerationIsExplodedNotOk) {
  for (const char* variant : {"euler", "rk4", "implicit"}) {
    const RunResult r = run(kMujoco, variant, stiff_spring());
    EXPECT_EQ(r.status, Status::Exploded) << variant << ": " << r.message;
    EXPECT_NE(r.message.find("mjWARN_BADQACC"), std::string::npos) << variant << ": " << r.message;
    // the trajectory stops before the reset: every kept sample is the engine's own motion
    ASSERT_FALSE(r.trajectory.samples.empty());
    EXPECT_LT(r.trajectory.samples.back().time, r.steps * stiff_spring().dt);
  }
}

TEST(Status, MujocoSoftSpringStaysOk) {
  const RunResult r = run(kMujoco, "euler", stiff_spring_scene(1e2));
  EXPECT_EQ(r.status, Status::Ok) << r.message;
}
#endif

#ifdef PHYSBENCH_HAVE_BOX2D
// Box2D scales a velocity that would move a body more than 2 m in a step down to that, silently.
// The adapter already refuses scenes that start near the limit; a body accelerated past it is
// caught as it happens.
Scene accelerated_planar_box(double acceleration) {
  Scene scene;
  scene.name = "fast-planar-box";
  scene.planar = true;
  scene.collisions = false;
  scene.gravity = Vec3(acceleration, 0.0, 0.0);
  scene.dt = 1.0 / 60.0;
  scene.duration = 0.5;
  BodySpec box;
  box.shape.half_extents = Vec3(0.5, 0.5, 0.5);
  scene.bodies = {box};
  scene.probe.metrics = {Metric::Energy};
  return scene;
}

TEST(Status, Box2dTranslationClampIsAnErrorNotOk) {
  // 1000 m/s² for 0.5 s ends at 500 m/s, 8 m a step: Box2D would move it 2
  try {
    const RunResult r = run("box2d", "default", accelerated_planar_box(1000.0));
    ADD_FAILURE() << "a clamped run was taken as a result: " << to_string(r.status) << " "
                  << r.message;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("b2_maxTranslation"), std::string::npos) << e.what();
  }
  // 100 m/s² ends at 50 m/s, 0.8 m a step: no clamp, and the box goes ½ a t² (plus semi-implicit
  // Euler's ½ a dt t = 0.42 m)
  const RunResult r = run("box2d", "default", accelerated_planar_box(100.0));
  ASSERT_EQ(r.status, Status::Ok) << r.message;
  EXPECT_NEAR(r.trajectory.samples.back().bodies[0].position.x(), 12.5 + 0.42, 0.05);
}
#endif

}  // namespace
