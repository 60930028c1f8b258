// Box2D adapter (2.4.1): planar scenes only. The scene's XY plane is Box2D's world; a body's
// rotation about z is Box2D's angle.
#include <box2d/box2d.h>

#include <cfloat>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "physbench/particle_driver.h"
#include "physbench/registry.h"
#include "physbench/springs.h"

namespace physbench {

namespace {

constexpr int kVelocityIterations = 8;  // Box2D's recommended default
constexpr int kPositionIterations = 3;  // Box2D's recommended default
constexpr int kEqualVelocityIterations = 10;  // the equal-iterations variant: every engine's 10
// a scene plane is an edge this long each way from the plane body's origin (m)
constexpr float kGroundHalfLength = 1000.0f;

// particles touch planes only: one collision category each
constexpr std::uint16_t kPlaneCategory = 0x0001, kParticleCategory = 0x0002;
// a plane is an edge this long each way from its point (m): far beyond any particle scene
constexpr float kPlaneHalfLength = 100.0f;
// particles: bounces below this normal speed are still restituted (Box2D's default, 1 m/s, would
// stop the bounce scene's particle after a few apexes); rigid bodies take the scene's
// kRestitutionThreshold, as every engine does
constexpr float kParticleRestitutionThreshold = 1e-3f;

double angle_about_z(const Quat& q) { return 2.0 * std::atan2(q.z(), q.w()); }

class Box2dEngine final : public Engine {
 public:
  Box2dEngine(bool spring_joints, int velocity_iterations)
      : spring_joints_(spring_joints), velocity_iterations_(velocity_iterations) {}

  // iterations: b2World::Step's velocity iterations (position iterations stay 3); substeps: N
  // calls of b2World::Step(dt/N) (Box2D 2.4 has none of its own)
  Tuning tune(const SolverKnobs& knobs) override {
    Tuning tuning;
    if (knobs.iterations > 0) {
      velocity_iterations_ = knobs.iterations;
      tuning.settings.push_back(
          {"velocity / position iterations",
           std::to_string(knobs.iterations) + " / " + std::to_string(kPositionIterations),
           "the sweep's value (--sweep-iterations): b2World::Step's velocity iterations"});
    }
    if (knobs.substeps > 0) {
      substeps_ = knobs.substeps;
      tuning.settings.push_back(swept_substeps(
          knobs.substeps, "N calls of b2World::Step(dt/N) (Box2D 2.4 has none of its own)"));
    }
    return tuning;
  }

  void load(const Scene& scene) override {
    scene_ = scene;
    contacts_.start(scene);
    dt_ = scene.dt;
    world_ = std::make_unique<b2World>(b2Vec2(float(scene.gravity.x()), float(scene.gravity.y())));
    world_->SetAllowSleeping(false);
    for (const BodySpec& b : scene.bodies) {
      b2BodyDef def;
      def.type = b.mass > 0.0 ? b2_dynamicBody : b2_staticBody;
      def.position.Set(float(b.position.x()), float(b.position.y()));
      def.angle = float(angle_about_z(b.orientation));
      def.linearVelocity.Set(float(b.linear_velocity.x()), float(b.linear_velocity.y()));
      def.angularVelocity = float(b.angular_velocity.z());
      def.allowSleep = false;
      b2Body* body = world_->CreateBody(&def);

      b2PolygonShape box;
      b2CircleShape circle;
      b2EdgeShape edge;
      b2FixtureDef fixture;
      if (b.shape.kind == ShapeKind::Box) {
        // every polygon carries a b2_polygonRadius (1 cm) skin: the core shrinks by it, so the
        // rounded box's faces are the scene's and exactly touching boxes start touching
        box.SetAsBox(float(b.shape.half_extents.x()) - b2_polygonRadius,
                     float(b.shape.half_extents.y()) - b2_polygonRadius);
        fixture.shape = &box;
      } else if (b.shape.kind == ShapeKind::Plane) {
        // the plane's line (local y = 0) as a long edge moved down by the edge's own skin
        edge.SetTwoSided(b2Vec2(-kGroundHalfLength, -b2_polygonRadius),
                         b2Vec2(kGroundHalfLength, -b2_polygonRadius));
        fixture.shape = &edge;
      } else {
        circle.m_radius = float(b.shape.radius);
        fixture.shape = &circle;
      }
      fixture.density = 1.0f;  // replaced below by the scene's mass properties
      // Box2D's own mixing is the scene's pair rule: √(μa μb) and max(ea, eb)
      fixture.friction = float(b.friction);
      fixture.restitution = float(b.restitution);
      fixture.restitutionThreshold = float(kRestitutionThreshold);
      if (!scene.collisions) fixture.filter.maskBits = 0;
      body->CreateFixture(&fixture);
      if (b.mass > 0.0) {
        // the scene's mass and its inertia about z: a sphere keeps its 3D inertia, not a disc's
        b2MassData mass;
        mass.mass = float(b.mass);
        mass.center.SetZero();
        mass.I = float(principal_inertia(b.shape, b.mass).z());
        body->SetMassData(&mass);
      }
      bodies_.push_back(body);
    }
    if (spring_joints_) create_spring_joints();
    if (scene.particles) create_particles();
  }

  // particles: a dynamic circle body each (the scene's radius and mass), the planes as edges of
  // one static body, filtered so that only particle–plane pairs collide
  void create_particles() {
    const ParticleSetSpec& p = *scene_.particles;
    driver_ = std::make_unique<ParticleDriver>(scene_);
    b2BodyDef ground_def;
    b2Body* ground = world_->CreateBody(&ground_def);
    for (const ParticlePlaneSpec& plane : p.planes) {
      // the edge's 1 cm skin (b2_polygonRadius) moved below the plane, so circles rest on it
      const b2Vec2 normal(float(plane.normal.x()), float(plane.normal.y()));
      const b2Vec2 along(-normal.y, normal.x);
      const b2Vec2 point =
          b2Vec2(float(plane.point.x()), float(plane.point.y())) - b2_polygonRadius * normal;
      b2EdgeShape edge;
      edge.SetTwoSided(point - kPlaneHalfLength * along, point + kPlaneHalfLength * along);
      b2FixtureDef fixture;
      fixture.shape = &edge;
      fixture.friction = float(p.friction);
      fixture.restitution = 0.0f;  // Box2D keeps the larger of the two: the particle's
      fixture.restitutionThreshold = kParticleRestitutionThreshold;
      fixture.filter.categoryBits = kPlaneCategory;
      fixture.filter.maskBits = kParticleCategory;
      ground->CreateFixture(&fixture);
    }
    first_particle_ = bodies_.size();
    b2CircleShape circle;
    circle.m_radius = float(p.radius);
    Shape sphere;
    sphere.kind = ShapeKind::Sphere;
    sphere.radius = p.radius;
    b2MassData mass;
    mass.mass = float(p.mass);
    mass.center.SetZero();
    mass.I = float(principal_inertia(sphere, p.mass).z());
    for (long i = 0; i < p.count; ++i) {
      const rtp::ParticleSpawn start = driver_->start(i);
      b2BodyDef def;
      def.type = b2_dynamicBody;
      def.position.Set(float(start.position.x()), float(start.position.y()));
      def.linearVelocity.Set(float(start.velocity.x()), float(start.velocity.y()));
      def.allowSleep = false;
      b2Body* body = world_->CreateBody(&def);
      b2FixtureDef fixture;
      fixture.shape = &circle;
      fixture.friction = float(p.friction);  // Box2D mixes frictions as √(a b): the scene's
      fixture.restitution = float(p.restitution);
      fixture.restitutionThreshold = kParticleRestitutionThreshold;
      fixture.filter.categoryBits = kParticleCategory;
      fixture.filter.maskBits = kPlaneCategory;
      body->CreateFixture(&fixture);
      body->SetMassData(&mass);
      bodies_.push_back(body);
    }
  }

  // the driver's forces from the state at the start of the step; Box2D clears them after
  void step_particles_before() {
    for (long i = 0; i < driver_->count(); ++i) {
      b2Body* body = bodies_[first_particle_ + std::size_t(i)];
      const b2Vec2 p = body->GetPosition(), v = body->GetLinearVelocity();
      const Vec3 f = driver_->force(i, Vec3(p.x, p.y, 0.0), Vec3(v.x, v.y, 0.0));
      body->ApplyForceToCenter(b2Vec2(float(f.x()), float(f.y())), true);
    }
  }

  void step_particles_after() {
    driver_->age(dt_, [this](long i, const rtp::ParticleSpawn& spawn) {
      b2Body* body = bodies_[first_particle_ + std::size_t(i)];
      body->SetTransform(b2Vec2(float(spawn.position.x()), float(spawn.position.y())), 0.0f);
      body->SetLinearVelocity(b2Vec2(float(spawn.velocity.x()), float(spawn.velocity.y())));
      body->SetAngularVelocity(0.0f);
    });
  }

  // springs as Box2D's own soft distance joint: rest length, stiffness (N/m) and damping (N s/m)
  // are the scene's; the joint is solved implicitly inside the velocity solver
  void create_spring_joints() {
    b2BodyDef ground_def;
    b2Body* ground = world_->CreateBody(&ground_def);
    for (const SpringSpec& s : scene_.springs) {
      b2DistanceJointDef def;
      def.bodyA = bodies_[s.body_a];
      def.localAnchorA.Set(float(s.local_point_a.x()), float(s.local_point_a.y()));
      def.bodyB = s.body_b >= 0 ? bodies_[s.body_b] : ground;
      def.localAnchorB.Set(float(s.point_b.x()),
                           float(s.point_b.y()));  // the ground sits at the origin
      def.length = float(s.rest_length);
      def.minLength = 0.0f;
      def.maxLength = FLT_MAX;
      def.stiffness = float(s.stiffness);
      def.damping = float(s.damping);
      world_->CreateJoint(&def);
    }
  }

  void apply_impulse(int b, const Vec3& impulse, const Vec3& point) override {
    bodies_[b]->ApplyLinearImpulse(b2Vec2(float(impulse.x()), float(impulse.y())),
                                   b2Vec2(float(point.x()), float(point.y())), true);
  }

  void step() override {
    // a sweep's substeps: N calls of Step(dt/N), each with the forces; a contact count a solve
    const int substeps = std::max(substeps_, 1);
    for (int k = 0; k < substeps; ++k) {
      // springs as external forces from the state at the start of the step; Box2D clears them
      // after
      if (!scene_.springs.empty() && !spring_joints_)
        apply_spring_forces(
            scene_, [this](int b) { return body_state(b); },
            [this](int b, const Vec3& f, const Vec3& p) {
              bodies_[b]->ApplyForce(b2Vec2(float(f.x()), float(f.y())),
                                     b2Vec2(float(p.x()), float(p.y())), true);
            });
      if (driver_) step_particles_before();
      world_->Step(float(dt_ / substeps), velocity_iterations_, kPositionIterations);
      if (contacts_.counting()) {
        // the touching contacts' manifold points this solve
        for (const b2Contact* c = world_->GetContactList(); c; c = c->GetNext())
          if (c->IsTouching()) contacts_.add(c->GetManifold()->pointCount);
        contacts_.end_step();
      }
    }
    ++steps_;
    if (driver_) step_particles_after();
    // Box2D scales down any velocity that would carry a body more than b2_maxTranslation (2 m)
    // or turn it more than b2_maxRotation (π/2) in one step, silently: the motion is then not the
    // scene's. A clamped velocity sits exactly at the limit.
    for (std::size_t i = 0; i < bodies_.size(); ++i) {
      const b2Body* body = bodies_[i];
      if (!body || body->GetType() != b2_dynamicBody) continue;
      const float h = float(dt_ / std::max(substeps_, 1));
      const float moved = body->GetLinearVelocity().Length() * h;
      // a particle is a point in the scene: the spin of the circle that stands for it is not
      const float turned =
          i < scene_.bodies.size() ? std::abs(body->GetAngularVelocity()) * h : 0.0f;
      if (moved >= 0.9999f * b2_maxTranslation || turned >= 0.9999f * b2_maxRotation) {
        std::ostringstream why;
        why << "Box2D clamped body " << i << "'s velocity to its per-step limit ("
            << (moved >= 0.9999f * b2_maxTranslation ? "b2_maxTranslation = 2 m" : "b2_maxRotation = π/2")
            << " per step at dt = " << dt_ << " s) at step " << steps_
            << ": the motion is not the scene's";
        throw std::runtime_error(why.str());
      }
    }
  }

  std::optional<ContactCount> contact_count() const override { return contacts_.count(); }

  SampledState body_state(int index) const override {
    const b2Body* body = bodies_[index];
    const b2Vec2 p = body->GetPosition();
    const b2Vec2 v = body->GetLinearVelocity();
    const double angle = body->GetAngle();
    return {Vec3(p.x, p.y, 0.0), Quat(Eigen::AngleAxisd(angle, Vec3::UnitZ())), Vec3(v.x, v.y, 0.0),
            Vec3(0.0, 0.0, body->GetAngularVelocity())};
  }

 private:
  Scene scene_;
  bool spring_joints_;
  int velocity_iterations_;
  double dt_ = 0.0;
  int substeps_ = 0;  // a sweep's substeps; 0: one step of dt
  std::unique_ptr<b2World> world_;
  long steps_ = 0;
  ContactTally contacts_;
  std::vector<b2Body*> bodies_;  // owned by world_; the particles follow the scene's bodies
  std::unique_ptr<ParticleDriver> driver_;
  std::size_t first_particle_ = 0;
};

}  // namespace

EngineInfo box2d_engine_info() {
  EngineInfo info;
  info.name = "box2d";
  info.variants = {"default", "joint", "iterations-10"};
  info.version = std::to_string(b2_version.major) + "." + std::to_string(b2_version.minor) + "." +
                 std::to_string(b2_version.revision) + " (as the library reports it)";
  info.unsupported = [](const Scene& scene, const std::string&) -> std::optional<std::string> {
    if (!scene.planar) return "Box2D is a 2D engine: the scene is not marked planar";
    if (auto why = peer_particles_unsupported(scene, "Box2D")) return why;
    if (scene.particles) {
      // Box2D clamps translation per step to b2_maxTranslation, silently
      const ParticleSetSpec& p = *scene.particles;
      const double fastest = std::max(p.velocity_min.norm(), p.velocity_max.norm());
      if (fastest * scene.dt > 0.5 * b2_maxTranslation)
        return "particles start near Box2D's per-step limit b2_maxTranslation";
    }
    for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
      const BodySpec& b = scene.bodies[i];
      if (b.shape.kind == ShapeKind::Box &&
          std::min(b.shape.half_extents.x(), b.shape.half_extents.y()) <= 2.0 * b2_polygonRadius)
        return "bodies[" + std::to_string(i) +
               "] is too thin for Box2D's 1 cm polygon skin (half extent <= 2 cm)";
      // Box2D clamps translation per step to b2_maxTranslation, silently
      if (b.linear_velocity.norm() * scene.dt > 0.5 * b2_maxTranslation)
        return "bodies[" + std::to_string(i) +
               "] moves near Box2D's per-step limit b2_maxTranslation";
      if (std::abs(b.angular_velocity.z()) * scene.dt > 0.5 * b2_maxRotation)
        return "bodies[" + std::to_string(i) + "] turns near Box2D's per-step limit b2_maxRotation";
    }
    return std::nullopt;
  };
  // joint differs only with springs, iterations-10 only where there are contacts to solve
  info.applies = [](const Scene& scene, const std::string& variant) {
    if (variant == "joint") return !scene.springs.empty();
    if (variant == "iterations-10") return scene.has_contacts();
    return true;
  };
  info.create = [](const std::string& variant) -> std::unique_ptr<Engine> {
    return std::make_unique<Box2dEngine>(
        variant == "joint",
        variant == "iterations-10" ? kEqualVelocityIterations : kVelocityIterations);
  };
  info.settings = [](const std::string& variant) {
    return std::vector<Setting>{
        variant == "iterations-10"
            ? Setting{"velocity / position iterations", "10 / 3",
                      "the equal-iterations variant: 10 velocity iterations, as every engine's"}
            : Setting{"velocity / position iterations", "8 / 3", "Box2D's recommended values"},
        {"polygon skin", "box cores shrunk by b2_polygonRadius (1 cm) on each side",
         "the rounded box's faces are the scene's: exactly touching boxes start touching, not "
         "2 cm overlapped"},
        {"planes", "a two-sided edge 1 km each way along the plane's line, moved 1 cm below it",
         "Box2D has no half-plane; the edge's skin then lies on the plane itself"},
        {"contact materials", "the scene's friction and restitution per fixture; restitution "
         "threshold 0.1 m/s (default 1 m/s)",
         "Box2D mixes friction as √(a b) and restitution as max(a, b): the scene's pair rule"},
        {"continuous collision", "Box2D's default: time of impact against static bodies",
         "the engine's own defaults; tunnelling scenes show what that does"},
        {"allow sleeping", "false (world and bodies)", "sleeping off in every engine"},
        {"mass properties", "from the scene (SetMassData, I = scene's Izz)",
         "same inertia in every engine"},
        {"collision mask", "0 when the scene has collisions off",
         "model only what the scene needs"},
        {"precision", "float", "Box2D computes in single precision"},
        {"particles",
         "a dynamic circle body each (scene radius and mass); planes as two-sided edges 100 m each "
         "way, moved 1 cm (b2_polygonRadius) below the plane; collision filtering lets only "
         "particle-plane pairs meet",
         "model only what the scene needs: no particle-particle contact; circles rest on the "
         "plane, not on the edge's skin"},
        {"particle contacts",
         "restitution e on particles, 0 on planes (Box2D keeps the larger); restitution threshold "
         "1e-3 m/s on both (default 1 m/s); friction the scene's on both (mixed as √(a b))",
         "Box2D's restitution and Coulomb friction stand in for the seed's per-bounce factors"},
        {"particle forces", "ApplyForceToCenter from the shared particle driver, once per step",
         "the same attractors, drag and wind as rtp, from the state at the step's start"},
        variant == "joint"
            ? Setting{"springs", "b2DistanceJoint: the scene's rest length, stiffness and damping",
                      "Box2D's native spring, solved implicitly in the velocity solver"}
            : Setting{"springs",
                      "external force (ApplyForce at the attachment point), once per step",
                      "the scene's spring law from the state at the start of the step"},
    };
  };
  state_instruction_set(info, "x86-64 baseline: SSE2 (Debian's libbox2d, generic build)",
                        "Debian builds for the architecture's baseline; rtp's -x86-64 variants "
                        "are the equal-instruction-set comparison");
  return info;
}

}  // namespace physbench
