// Bullet adapter. Compiled twice: against the single-precision library into the main
// executable (variant "float") and against the double-precision one, with
// BT_USE_DOUBLE_PRECISION, into physbench-bullet64 (variant "double"). The two builds export
// the same symbols, so they never share a process.
#include <btBulletDynamicsCommon.h>

#include <cmath>

#include "bullet_version.h"
#include "physbench/particle_driver.h"
#include "physbench/registry.h"
#include "physbench/springs.h"

namespace physbench {

namespace {

#ifdef BT_USE_DOUBLE_PRECISION
constexpr const char* kVariant = "double";
#else
constexpr const char* kVariant = "float";
#endif

btVector3 to_bt(const Vec3& v) {
  return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z()));
}
btQuaternion to_bt(const Quat& q) {
  return btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w()));
}
Vec3 from_bt(const btVector3& v) { return Vec3(v.x(), v.y(), v.z()); }

// the scene's pair rule (docs/scene-format.md) in place of Bullet's product of the two values;
// Bullet calls these for every new contact point (btManifoldResult::addContactPoint)
btScalar pair_friction_rule(const btCollisionObject* a, const btCollisionObject* b) {
  return btSqrt(a->getFriction() * b->getFriction());
}
btScalar pair_restitution_rule(const btCollisionObject* a, const btCollisionObject* b) {
  return btMax(a->getRestitution(), b->getRestitution());
}

class BulletEngine final : public Engine {
 public:
  // iterations: btContactSolverInfo::m_numIterations; substeps: stepSimulation(dt/N, 0) N times,
  // each a whole internal step of dt/N (no accumulator: maxSubSteps = 0 steps exactly the time
  // given, and the adapter reads the centre-of-mass transform, which is not interpolated)
  Tuning tune(const SolverKnobs& knobs) override {
    Tuning tuning;
    if (knobs.iterations > 0) {
      iterations_ = knobs.iterations;
      tuning.settings.push_back(
          {"solver",
           "btSequentialImpulseConstraintSolver, " + std::to_string(knobs.iterations) +
               " iterations",
           "the sweep's value (--sweep-iterations): btContactSolverInfo::m_numIterations"});
    }
    if (knobs.substeps > 0) {
      substeps_ = knobs.substeps;
      tuning.settings.push_back(swept_substeps(knobs.substeps, "stepSimulation(dt/N, 0) N times"));
    }
    return tuning;
  }

  ~BulletEngine() override {
    // tear the world down wholesale: removing bodies one by one is O(bodies × pairs)
    world_.reset();
    bodies_.clear();
  }

  void load(const Scene& scene) override {
    scene_ = scene;
    dt_ = scene.dt;
    contacts_.start(scene);
    configuration_ = std::make_unique<btDefaultCollisionConfiguration>();
    // a box meeting a plane gets its whole manifold at once (perturbed queries), not one point
    // the first step and more later: with one point, a box dropped flat on the ground took an
    // off-centre impulse and tumbled. Not for particles: a sphere has one point, and would pay
    // for three perturbed queries every step
    if (!scene.particles) configuration_->setPlaneConvexMultipointIterations(3, 3);
    dispatcher_ = std::make_unique<btCollisionDispatcher>(configuration_.get());
    broadphase_ = std::make_unique<btDbvtBroadphase>();
    solver_ = std::make_unique<btSequentialImpulseConstraintSolver>();
    world_ = std::make_unique<btDiscreteDynamicsWorld>(dispatcher_.get(), broadphase_.get(),
                                                       solver_.get(), configuration_.get());
    world_->setGravity(to_bt(scene.gravity));
    // Particles: Bullet resolves a penetration shallower than 4 cm (its split-impulse threshold)
    // with Baumgarte velocity, which a bouncing body keeps: a 1 cm sphere arriving at 4.4 m/s
    // sank 2.2 cm and rose to 0.84 m instead of 0.64 m. Split impulse at every depth moves it out
    // without adding speed. Bodies keep Bullet's default: with split impulse at every depth the
    // 10-box tower fell over (8 m of drift in 10 s; 0.50 m at the default).
    world_->getSolverInfo().m_splitImpulse = 1;
    if (scene.particles) world_->getSolverInfo().m_splitImpulsePenetrationThreshold = 0;
    // restitution only above the scene's threshold (Bullet's default is 0.2 m/s)
    world_->getSolverInfo().m_restitutionVelocityThreshold = btScalar(kRestitutionThreshold);
    // a sweep's iterations: the sequential-impulse solver's (btContactSolverInfo::m_numIterations)
    if (iterations_ > 0) world_->getSolverInfo().m_numIterations = iterations_;
    // each body carries the scene's own material; the pair takes √(μa μb) and max(ea, eb)
    gCalculateCombinedFrictionCallback = &pair_friction_rule;
    gCalculateCombinedRestitutionCallback = &pair_restitution_rule;

    for (const BodySpec& b : scene.bodies) {
      std::unique_ptr<btCollisionShape> shape;
      btTransform pose(to_bt(b.orientation), to_bt(b.position));
      switch (b.shape.kind) {
        case ShapeKind::Box:
          shape = std::make_unique<btBoxShape>(to_bt(b.shape.half_extents));
          break;
        case ShapeKind::Sphere:
          shape = std::make_unique<btSphereShape>(btScalar(b.shape.radius));
          break;
        case ShapeKind::Plane: {
          // the scene's plane is the body's local y = 0: Bullet's plane takes a normal and offset
          const Vec3 normal = b.orientation * Vec3::UnitY();
          shape =
              std::make_unique<btStaticPlaneShape>(to_bt(normal), btScalar(normal.dot(b.position)));
          pose.setIdentity();
          break;
        }
      }
      // the scene's mass properties, not Bullet's own, so every engine integrates the same body
      const btVector3 inertia =
          b.mass > 0.0 ? to_bt(principal_inertia(b.shape, b.mass)) : btVector3(0, 0, 0);
      btRigidBody::btRigidBodyConstructionInfo info(btScalar(b.mass), nullptr, shape.get(),
                                                    inertia);
      info.m_startWorldTransform = pose;
      // the body's own material: the pair callbacks above combine two of them
      info.m_friction = btScalar(b.friction);
      info.m_restitution = btScalar(b.restitution);
      auto body = std::make_unique<btRigidBody>(info);
      body->setActivationState(DISABLE_DEACTIVATION);
      body->setFlags(body->getFlags() | BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY);
      if (b.mass > 0.0) {
        body->setLinearVelocity(to_bt(b.linear_velocity));
        body->setAngularVelocity(to_bt(b.angular_velocity));
      }
      // a scene without collisions collides nothing: mask 0 keeps every pair out
      const int group = 1;
      const int mask = scene.collisions ? -1 : 0;
      world_->addRigidBody(body.get(), group, mask);
      shapes_.push_back(std::move(shape));
      bodies_.push_back(std::move(body));
    }
    if (scene.particles) create_particles();
  }

  // particles: one rigid sphere each (the scene's radius and mass), sharing one shape; planes as
  // static plane bodies. Collision groups let a particle meet planes only — Bullet still finds
  // particle pairs in its broad phase and rejects them there (its filter runs on the pairs it
  // found), which it pays for.
  void create_particles() {
    constexpr int kPlaneGroup = 2, kParticleGroup = 4;
    const ParticleSetSpec& p = *scene_.particles;
    driver_ = std::make_unique<ParticleDriver>(scene_);
    first_particle_ = bodies_.size();
    shapes_.push_back(std::make_unique<btSphereShape>(btScalar(p.radius)));
    btCollisionShape* sphere = shapes_.back().get();
    btVector3 inertia(0, 0, 0);
    sphere->calculateLocalInertia(btScalar(p.mass), inertia);
    for (long i = 0; i < p.count; ++i) {
      const rtp::ParticleSpawn start = driver_->start(i);
      btRigidBody::btRigidBodyConstructionInfo info(btScalar(p.mass), nullptr, sphere, inertia);
      info.m_startWorldTransform = btTransform(btQuaternion::getIdentity(), to_bt(start.position));
      info.m_friction = btScalar(p.friction);
      info.m_restitution = btScalar(p.restitution);
      auto body = std::make_unique<btRigidBody>(info);
      body->setActivationState(DISABLE_DEACTIVATION);
      body->setLinearVelocity(to_bt(start.velocity));
      world_->addRigidBody(body.get(), kParticleGroup, kPlaneGroup);
      bodies_.push_back(std::move(body));
    }
    for (const ParticlePlaneSpec& plane : p.planes) {
      shapes_.push_back(std::make_unique<btStaticPlaneShape>(
          to_bt(plane.normal), btScalar(plane.normal.dot(plane.point))));
      btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shapes_.back().get());
      info.m_friction = btScalar(p.friction);
      info.m_restitution = btScalar(p.restitution);
      planes_.push_back(std::make_unique<btRigidBody>(info));
      world_->addRigidBody(planes_.back().get(), kPlaneGroup, kParticleGroup);
    }
  }

  void apply_impulse(int b, const Vec3& impulse, const Vec3& point) override {
    btRigidBody& body = *bodies_[b];
    body.applyImpulse(to_bt(impulse), to_bt(point) - body.getCenterOfMassPosition());
  }

  void step() override {
    // a sweep's substeps: N whole internal steps of dt/N, the step's forces each (Bullet clears
    // them after every stepSimulation); the particles age once a step
    const int substeps = std::max(substeps_, 1);
    for (int k = 0; k < substeps; ++k) {
      apply_forces();
      // maxSubSteps = 0: exactly one internal step of the time given, no accumulator or
      // interpolation
      world_->stepSimulation(btScalar(dt_ / substeps), 0);
    }
    if (contacts_.counting()) {
      // the persistent manifolds' points the solver held this step (its last substep's)
      for (int m = 0; m < dispatcher_->getNumManifolds(); ++m)
        contacts_.add(dispatcher_->getManifoldByIndexInternal(m)->getNumContacts());
      contacts_.end_step();
    }
    if (driver_)
      driver_->age(dt_, [this](long i, const rtp::ParticleSpawn& spawn) {
        btRigidBody& body = *bodies_[first_particle_ + i];
        body.setCenterOfMassTransform(
            btTransform(btQuaternion::getIdentity(), to_bt(spawn.position)));
        body.setLinearVelocity(to_bt(spawn.velocity));
        body.setAngularVelocity(btVector3(0, 0, 0));
      });
  }

  std::optional<ContactCount> contact_count() const override { return contacts_.count(); }

 private:
  // the springs', the particles' drag, wind and attractors, as external forces from the state now
  void apply_forces() {
    // springs as external forces from the state at the start of the step; Bullet clears them after
    if (!scene_.springs.empty())
      apply_spring_forces(
          scene_, [this](int b) { return body_state(b); },
          [this](int b, const Vec3& force, const Vec3& point) {
            btRigidBody& body = *bodies_[b];
            body.applyForce(to_bt(force), to_bt(point) - body.getCenterOfMassPosition());
          });
    // particles: drag, wind and attractors as central forces from the state at the start of the
    // step
    if (driver_)
      for (long i = 0; i < driver_->count(); ++i) {
        btRigidBody& body = *bodies_[first_particle_ + i];
        body.applyCentralForce(to_bt(driver_->force(i, from_bt(body.getCenterOfMassPosition()),
                                                    from_bt(body.getLinearVelocity()))));
      }
  }

 public:
  SampledState body_state(int index) const override {
    const btRigidBody& body = *bodies_[index];
    const btTransform& t = body.getCenterOfMassTransform();
    const btQuaternion q = t.getRotation();
    return {from_bt(t.getOrigin()), Quat(q.w(), q.x(), q.y(), q.z()),
            from_bt(body.getLinearVelocity()), from_bt(body.getAngularVelocity())};
  }

 private:
  Scene scene_;
  double dt_ = 0.0;
  ContactTally contacts_;
  int iterations_ = 0;  // a sweep's solver iterations; 0: Bullet's default (10)
  int substeps_ = 0;    // a sweep's substeps; 0: one step of dt
  std::unique_ptr<btDefaultCollisionConfiguration> configuration_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<btRigidBody>> bodies_;
  std::vector<std::unique_ptr<btRigidBody>> planes_;
  std::unique_ptr<ParticleDriver> driver_;
  std::size_t first_particle_ = 0;
  std::unique_ptr<btDiscreteDynamicsWorld> world_;  // declared last: destroyed first
};

}  // namespace

EngineInfo bullet_engine_info() {
  EngineInfo info;
  info.name = "bullet";
  info.variants = {kVariant};
  info.version = bullet_version(kVariant);
  info.unsupported = [](const Scene& scene,
                        const std::string& variant) -> std::optional<std::string> {
    if (variant != kVariant)
      return "this executable links Bullet's " + std::string(kVariant) + " build, not " + variant;
    if (auto why = peer_particles_unsupported(scene, "Bullet")) return why;
    return std::nullopt;
  };
  info.create = [](const std::string&) -> std::unique_ptr<Engine> {
    return std::make_unique<BulletEngine>();
  };
  info.settings = [](const std::string&) {
    return std::vector<Setting>{
        {"precision", kVariant,
         "the variant: Bullet's float or double library, each in its own process"},
        {"stepSimulation maxSubSteps", "0",
         "one internal step of exactly dt per call; no interpolation"},
        {"activation state", "DISABLE_DEACTIVATION", "sleeping off in every engine"},
        {"rigid body flags", "+BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY",
         "gyroscopic torque on, as in every engine"},
        {"mass properties", "from the scene", "inertia set explicitly, same as every engine"},
        {"friction, restitution",
         "the scene's value per body; the pair combined as √(μa μb) and max(ea, eb) by "
         "gCalculateCombinedFrictionCallback / gCalculateCombinedRestitutionCallback",
         "the scene's pair rule; Bullet's own callbacks multiply the two values"},
        {"restitution velocity threshold", "0.1 m/s (default 0.2 m/s)",
         "the scene's threshold: slower impacts are inelastic in every engine that has one"},
        {"solver", "btSequentialImpulseConstraintSolver, 10 iterations (Bullet's default)",
         "Bullet's defaults are already the equal-iterations setting (10): one variant"},
        {"collision margin", "0.04 m on boxes (Bullet's default)",
         "btBoxShape keeps its margin inside the box, so the box is its true size; contacts "
         "are kept within the 0.02 m breaking threshold (default)"},
        {"plane-convex multipoint iterations", "3, 3 (default off; not for particle scenes)",
         "a box on a plane gets its whole manifold in the first step of contact; with Bullet's "
         "single point a box dropped flat took an off-centre impulse and tumbled"},
        {"continuous collision", "off (Bullet's default: ccd motion threshold 0)",
         "the engine's own defaults; tunnelling scenes show what that does"},
        {"collision mask", "0 when the scene has collisions off",
         "model only what the scene needs"},
        {"broadphase", "btDbvtBroadphase", "Bullet's recommended default"},
        {"particles",
         "rigid spheres (scene radius and mass, one shared shape) colliding with static planes "
         "only through "
         "collision groups; drag, wind, attractors as applyCentralForce each step",
         "model only what the scene needs; Bullet's broad phase still sees particle pairs"},
        {"particle contact solver",
         "split impulse at every penetration depth (threshold 0, default -0.04 m); scenes of "
         "bodies keep the default (a 10-box tower fell over at 0)",
         "Baumgarte correction of shallow penetrations adds bounce: apex 0.84 m for e = 0.8 "
         "instead of 0.64 m"},
        {"particle contacts", "the scene's friction and restitution on particle and plane",
         "the pair rule gives the scene's values; Bullet's friction is Coulomb, the scene's a "
         "velocity fraction"},
        {"springs", "external force (applyForce at the attachment point), once per step",
         "the scene's spring law from the state at the start of the step; Bullet's own springs are "
         "constraints"},
    };
  };
  state_instruction_set(info, "x86-64 baseline: SSE2 (Debian's libbullet, generic build)",
                        "Debian builds for the architecture's baseline; rtp's -x86-64 variants "
                        "are the equal-instruction-set comparison");
  return info;
}

}  // namespace physbench
