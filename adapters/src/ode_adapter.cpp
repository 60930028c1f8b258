// ODE adapter (0.16, double precision). ODE has no "up": gravity is the scene's vector.
#include <ode/ode.h>

#include <cstdarg>
#include <cstdio>
#include <stdexcept>

#include "physbench/particle_driver.h"
#include "physbench/registry.h"
#include "physbench/springs.h"

#ifndef PHYSBENCH_ODE_VERSION
#define PHYSBENCH_ODE_VERSION "unknown"
#endif

namespace physbench {

namespace {

// ODE reports a failed solve (e.g. "LCP internal error" from dWorldStep's Dantzig solver on
// degenerate contact sets) through its message handler and carries on with a wrong answer: the
// adapter counts them and turns the step into an error, so a failed solve is never a result
thread_local std::string ode_last_message;
thread_local long ode_messages = 0;

void record_ode_message(int number, const char* format, va_list arguments) {
  char text[512];
  std::vsnprintf(text, sizeof text, format, arguments);
  ode_last_message = "ODE message " + std::to_string(number) + ": " + text;
  ++ode_messages;
}

// dInitODE2 once per process, dCloseODE at exit
struct OdeLibrary {
  OdeLibrary() {
    dInitODE2(0);
    dSetMessageHandler(&record_ode_message);
  }
  ~OdeLibrary() { dCloseODE(); }
};

void ensure_ode_initialised() { static OdeLibrary library; }

// contact points ODE may report per pair (dBoxBox clips up to 8, a box on a plane gives 4)
constexpr int kMaxContactsPerPair = 8;
// QuickStep iterations of the equal-iterations variant, against ODE's default of 20
constexpr int kEqualIterations = 10;
// dWorldStep factorises each island's whole constraint matrix, O(rows³): a 20-box tower is
// about 240 rows; a 55-box pyramid is already thousands
constexpr int kMaxStepBodies = 20;

class OdeEngine final : public Engine {
 public:
  OdeEngine(bool quick_step, bool spring_joints, int iterations)
      : quick_step_(quick_step), spring_joints_(spring_joints), iterations_(iterations) {}

  // iterations: QuickStep's (dWorldSetQuickStepNumIterations), dWorldStep has none; substeps: N
  // steps of dt/N (ODE has no substeps of its own: its users step smaller), contacts found anew
  // for each
  Tuning tune(const SolverKnobs& knobs) override {
    Tuning tuning;
    if (knobs.iterations > 0) {
      if (!quick_step_)
        return {{}, "dWorldStep solves each step's constraints directly (Dantzig LCP): it has no "
                    "iteration count"};
      iterations_ = knobs.iterations;
      tuning.settings.push_back(
          {"stepper", "dWorldQuickStep, " + std::to_string(knobs.iterations) + " iterations",
           "the sweep's value (--sweep-iterations): dWorldSetQuickStepNumIterations"});
    }
    if (knobs.substeps > 0) {
      substeps_ = knobs.substeps;
      tuning.settings.push_back(swept_substeps(
          knobs.substeps, "N steps of dt/N, contacts found for each (ODE has none of its own)"));
    }
    return tuning;
  }
  ~OdeEngine() override {
    for (dGeomID plane : planes_) dGeomDestroy(plane);
    if (particle_space_) dSpaceDestroy(particle_space_);  // destroys its sphere geoms too
    if (space_) dSpaceDestroy(space_);                    // and the contact scene's geoms
    if (contacts_) dJointGroupDestroy(contacts_);
    if (world_) dWorldDestroy(world_);
  }

  void load(const Scene& scene) override {
    ensure_ode_initialised();
    // dWorldQuickStep shuffles constraint order with ODE's global generator: seed every run
    dRandSetSeed(0);
    scene_ = scene;
    dt_ = scene.dt;
    h_ = dt_ / std::max(substeps_, 1);
    contact_tally_.start(scene);
    world_ = dWorldCreate();
    dWorldSetGravity(world_, scene.gravity.x(), scene.gravity.y(), scene.gravity.z());
    dWorldSetAutoDisableFlag(world_, 0);
    if (iterations_ > 0) dWorldSetQuickStepNumIterations(world_, iterations_);
    for (const BodySpec& b : scene.bodies) {
      if (b.mass == 0.0) {
        // static bodies are geometry only in ODE; with no contacts yet they are only a pose
        bodies_.push_back(nullptr);
        continue;
      }
      dBodyID body = dBodyCreate(world_);
      const Vec3 inertia = principal_inertia(b.shape, b.mass);
      dMass mass;
      dMassSetParameters(&mass, b.mass, 0, 0, 0, inertia.x(), inertia.y(), inertia.z(), 0, 0, 0);
      dBodySetMass(body, &mass);
      dBodySetPosition(body, b.position.x(), b.position.y(), b.position.z());
      const dQuaternion q = {b.orientation.w(), b.orientation.x(), b.orientation.y(),
                             b.orientation.z()};
      dBodySetQuaternion(body, q);
      dBodySetLinearVel(body, b.linear_velocity.x(), b.linear_velocity.y(), b.linear_velocity.z());
      dBodySetAngularVel(body, b.angular_velocity.x(), b.angular_velocity.y(),
                         b.angular_velocity.z());
      dBodySetAutoDisableFlag(body, 0);
      dBodySetGyroscopicMode(body, 1);
      bodies_.push_back(body);
    }
    if (spring_joints_) create_spring_joints();
    if (scene.particles) create_particles();
    if (scene.has_contacts()) create_geoms();
  }

  // contact scenes: a geom per body in one hash space; static bodies are geoms without a body
  // (a plane is ODE's plane geom, n · x = d). Each geom's data is its scene index.
  void create_geoms() {
    space_ = dHashSpaceCreate(nullptr);
    if (!contacts_) contacts_ = dJointGroupCreate(0);
    for (std::size_t i = 0; i < scene_.bodies.size(); ++i) {
      const BodySpec& b = scene_.bodies[i];
      dGeomID geom = nullptr;
      switch (b.shape.kind) {
        case ShapeKind::Box: {
          const Vec3 size = 2.0 * b.shape.half_extents;
          geom = dCreateBox(space_, size.x(), size.y(), size.z());
          break;
        }
        case ShapeKind::Sphere:
          geom = dCreateSphere(space_, b.shape.radius);
          break;
        case ShapeKind::Plane: {
          const Vec3 n = b.orientation * Vec3::UnitY();
          geom = dCreatePlane(space_, n.x(), n.y(), n.z(), n.dot(b.position));
          break;
        }
      }
      dGeomSetData(geom, reinterpret_cast<void*>(i));
      if (bodies_[i]) {
        dGeomSetBody(geom, bodies_[i]);
      } else if (b.shape.kind != ShapeKind::Plane) {
        dGeomSetPosition(geom, b.position.x(), b.position.y(), b.position.z());
        const dQuaternion q = {b.orientation.w(), b.orientation.x(), b.orientation.y(),
                               b.orientation.z()};
        dGeomSetQuaternion(geom, q);
      }
    }
  }

  // a contact joint per point, with the scene's pair rule: μ = √(μa μb), bounce = max(ea, eb)
  static void body_contact(void* data, dGeomID a, dGeomID b) {
    auto* self = static_cast<OdeEngine*>(data);
    dBodyID body_a = dGeomGetBody(a), body_b = dGeomGetBody(b);
    if (!body_a && !body_b) return;  // two static geoms
    dContact contact[kMaxContactsPerPair];
    const int count = dCollide(a, b, kMaxContactsPerPair, &contact[0].geom, sizeof(dContact));
    if (count == 0) return;
    const BodySpec& spec_a = self->scene_.bodies[reinterpret_cast<std::size_t>(dGeomGetData(a))];
    const BodySpec& spec_b = self->scene_.bodies[reinterpret_cast<std::size_t>(dGeomGetData(b))];
    const double mu = pair_friction(spec_a, spec_b), bounce = pair_restitution(spec_a, spec_b);
    for (int i = 0; i < count; ++i) {
      // Approx1: the friction pyramid, its limit μ times the normal force (Coulomb); without
      // it ODE's mu is a fixed force limit
      contact[i].surface.mode = dContactApprox1 | (bounce > 0.0 ? dContactBounce : 0);
      contact[i].surface.mu = mu;
      contact[i].surface.bounce = bounce;
      contact[i].surface.bounce_vel = kRestitutionThreshold;
      dJointID joint = dJointCreateContact(self->world_, self->contacts_, &contact[i]);
      dJointAttach(joint, body_a, body_b);
    }
    self->contact_tally_.add(count);
  }

  // particles: a dBody sphere each (the scene's radius and mass) in a simple space, and the planes
  // as ODE plane geoms outside it; only plane–sphere pairs are ever tested (dSpaceCollide2)
  void create_particles() {
    const ParticleSetSpec& p = *scene_.particles;
    driver_ = std::make_unique<ParticleDriver>(scene_);
    particle_space_ = dSimpleSpaceCreate(nullptr);
    contacts_ = dJointGroupCreate(0);
    first_particle_ = bodies_.size();
    for (long i = 0; i < p.count; ++i) {
      dBodyID body = dBodyCreate(world_);
      dMass mass;
      dMassSetSphereTotal(&mass, p.mass, p.radius);
      dBodySetMass(body, &mass);
      const rtp::ParticleSpawn start = driver_->start(i);
      dBodySetPosition(body, start.position.x(), start.position.y(), start.position.z());
      dBodySetLinearVel(body, start.velocity.x(), start.velocity.y(), start.velocity.z());
      dBodySetAutoDisableFlag(body, 0);
      dGeomID sphere = dCreateSphere(particle_space_, p.radius);
      dGeomSetBody(sphere, body);
      bodies_.push_back(body);
    }
    for (const ParticlePlaneSpec& plane : p.planes)
      planes_.push_back(dCreatePlane(nullptr, plane.normal.x(), plane.normal.y(), plane.normal.z(),
                                     plane.normal.dot(plane.point)));
  }

  static void particle_contact(void* data, dGeomID a, dGeomID b) {
    auto* self = static_cast<OdeEngine*>(data);
    dContact contact{};
    if (dCollide(a, b, 1, &contact.geom, sizeof(dContact)) == 0) return;
    contact.surface.mode = dContactBounce;
    contact.surface.mu = self->scene_.particles->friction;
    contact.surface.bounce = self->scene_.particles->restitution;
    contact.surface.bounce_vel = 0.0;
    dJointID joint = dJointCreateContact(self->world_, self->contacts_, &contact);
    dJointAttach(joint, dGeomGetBody(a), dGeomGetBody(b));
  }

  void step_particles_before() {
    for (long i = 0; i < driver_->count(); ++i) {
      dBodyID body = bodies_[first_particle_ + i];
      const dReal* p = dBodyGetPosition(body);
      const dReal* v = dBodyGetLinearVel(body);
      const Vec3 f = driver_->force(i, Vec3(p[0], p[1], p[2]), Vec3(v[0], v[1], v[2]));
      dBodyAddForce(body, f.x(), f.y(), f.z());
    }
    for (dGeomID plane : planes_)
      dSpaceCollide2(plane, reinterpret_cast<dGeomID>(particle_space_), this, &particle_contact);
  }

  void step_particles_after() {
    dJointGroupEmpty(contacts_);
    driver_->age(dt_, [this](long i, const rtp::ParticleSpawn& spawn) {
      dBodyID body = bodies_[first_particle_ + i];
      dBodySetPosition(body, spawn.position.x(), spawn.position.y(), spawn.position.z());
      dBodySetLinearVel(body, spawn.velocity.x(), spawn.velocity.y(), spawn.velocity.z());
      dBodySetAngularVel(body, 0, 0, 0);
    });
  }

  // ODE has no impulse call: the velocity change is set directly
  void apply_impulse(int b, const Vec3& impulse, const Vec3& point) override {
    const SampledState now = body_state(b);
    const VelocityChange change = impulse_velocity_change(scene_.bodies[b], now, impulse, point);
    const Vec3 v = now.linear_velocity + change.linear, w = now.angular_velocity + change.angular;
    dBodySetLinearVel(bodies_[b], v.x(), v.y(), v.z());
    dBodySetAngularVel(bodies_[b], w.x(), w.y(), w.z());
  }

  void step() override {
    ++steps_;
    // a sweep's substeps: N steps of h = dt/N, each with its forces and contacts; a contact count
    // a solve
    for (int k = 0; k < std::max(substeps_, 1); ++k) {
      // springs as external forces from the state at the start of the step; ODE clears them
      // after
      if (!scene_.springs.empty() && !spring_joints_)
        apply_spring_forces(
            scene_, [this](int b) { return body_state(b); },
            [this](int b, const Vec3& f, const Vec3& p) {
              dBodyAddForceAtPos(bodies_[b], f.x(), f.y(), f.z(), p.x(), p.y(), p.z());
            });
      if (driver_) step_particles_before();
      if (space_) {
        dSpaceCollide(space_, this, &body_contact);
        contact_tally_.end_step();
      }
      ode_messages = 0;
      if (quick_step_)
        dWorldQuickStep(world_, h_);
      else
        dWorldStep(world_, h_);
      if (ode_messages > 0)
        throw std::runtime_error(ode_last_message + " (step " + std::to_string(steps_) +
                                 "): ODE's solver failed, so the run is not a result");
      if (driver_ || space_) dJointGroupEmpty(contacts_);
    }
    if (driver_) step_particles_after();
  }

  // the contact joints made for the bodies' geoms (a joint a point), summed since load()
  std::optional<ContactCount> contact_count() const override {
    if (!space_) return std::nullopt;
    return contact_tally_.count();
  }

  SampledState body_state(int index) const override {
    dBodyID body = bodies_[index];
    if (!body)
      return {scene_.bodies[index].position, scene_.bodies[index].orientation, Vec3::Zero(),
              Vec3::Zero()};
    const dReal* p = dBodyGetPosition(body);
    const dReal* q = dBodyGetQuaternion(body);
    const dReal* v = dBodyGetLinearVel(body);
    const dReal* w = dBodyGetAngularVel(body);
    return {Vec3(p[0], p[1], p[2]), Quat(q[0], q[1], q[2], q[3]), Vec3(v[0], v[1], v[2]),
            Vec3(w[0], w[1], w[2])};
  }

 private:
  // springs as ODE's own soft constraint: a distance joint (DBall) whose ERP and CFM give the
  // spring's stiffness and damping at this step: ERP = h k / (h k + c), CFM = 1 / (h k + c)
  // (ODE manual, "How to use ERP and CFM"). Implicit, so it holds at any stiffness — and damps.
  void create_spring_joints() {
    for (const SpringSpec& s : scene_.springs) {
      const SampledState a = body_state(s.body_a);
      const Vec3 point_a = a.position + a.orientation * s.local_point_a;
      Vec3 point_b = s.point_b;
      dBodyID body_b = nullptr;
      if (s.body_b >= 0) {
        const SampledState b = body_state(s.body_b);
        point_b = b.position + b.orientation * s.point_b;
        body_b = bodies_[s.body_b];
      }
      dJointID joint = dJointCreateDBall(world_, nullptr);
      dJointAttach(joint, bodies_[s.body_a], body_b);
      dJointSetDBallAnchor1(joint, point_a.x(), point_a.y(), point_a.z());
      dJointSetDBallAnchor2(joint, point_b.x(), point_b.y(), point_b.z());
      dJointSetDBallDistance(joint, s.rest_length);
      const double hk = h_ * s.stiffness;
      dJointSetDBallParam(joint, dParamERP, hk / (hk + s.damping));
      dJointSetDBallParam(joint, dParamCFM, 1.0 / (hk + s.damping));
    }
  }

  bool quick_step_;
  bool spring_joints_;
  int iterations_;  // QuickStep iterations; 0: ODE's default
  long steps_ = 0;
  ContactTally contact_tally_;  // contact joints for the bodies' geoms (contacts_ is their group)
  dSpaceID space_ = nullptr;
  std::unique_ptr<ParticleDriver> driver_;
  std::size_t first_particle_ = 0;
  dSpaceID particle_space_ = nullptr;
  dJointGroupID contacts_ = nullptr;
  std::vector<dGeomID> planes_;
  Scene scene_;
  double dt_ = 0.0;
  double h_ = 0.0;    // a solve's step: dt / substeps
  int substeps_ = 0;  // a sweep's substeps; 0: one step of dt
  dWorldID world_ = nullptr;
  std::vector<dBodyID> bodies_;
};

}  // namespace

EngineInfo ode_engine_info() {
  EngineInfo info;
  info.name = "ode";
  info.variants = {"quickstep", "step", "step-joint", "quickstep-10"};
  ensure_ode_initialised();
  info.version = std::string(PHYSBENCH_ODE_VERSION) + " (" + dGetConfiguration() + ")";
  info.unsupported = [](const Scene& scene,
                        const std::string& variant) -> std::optional<std::string> {
    if (auto why = peer_particles_unsupported(scene, "ODE")) return why;
    if (scene.has_contacts() && scene.particles)
      return "bodies in contact together with particles are not mapped onto ODE";
    if (scene.has_contacts() && variant != "quickstep" && variant != "quickstep-10") {
      int dynamic = 0;
      for (const BodySpec& b : scene.bodies) dynamic += b.mass > 0.0;
      if (dynamic > kMaxStepBodies)
        return "dWorldStep factorises the whole island's constraint matrix (O(rows³)): over " +
               std::to_string(kMaxStepBodies) + " bodies in contact it takes minutes per step";
    }
    return std::nullopt;
  };
  info.create = [](const std::string& variant) -> std::unique_ptr<Engine> {
    const bool quick = variant == "quickstep" || variant == "quickstep-10";
    return std::make_unique<OdeEngine>(quick, variant == "step-joint",
                                       variant == "quickstep-10" ? kEqualIterations : 0);
  };
  // step-joint differs only with springs, quickstep-10 only where there are contacts to solve
  info.applies = [](const Scene& scene, const std::string& variant) {
    if (variant == "step-joint") return !scene.springs.empty();
    if (variant == "quickstep-10") return scene.has_contacts();
    return true;
  };
  info.settings = [](const std::string& variant) {
    return std::vector<Setting>{
        {"stepper",
         variant == "quickstep"      ? "dWorldQuickStep (20 iterations, ODE default)"
         : variant == "quickstep-10" ? "dWorldQuickStep, 10 iterations"
                                     : "dWorldStep",
         variant == "quickstep-10" ? "the equal-iterations variant: 10, as every engine's"
                                   : "the variant"},
        {"dRandSetSeed", "0 before each run",
         "QuickStep shuffles constraints with a global generator"},
        {"auto-disable", "off (world and every body)", "sleeping off in every engine"},
        {"gyroscopic mode", "on", "stated explicitly; ODE's default"},
        {"mass properties", "from the scene (dMassSetParameters)", "same inertia in every engine"},
        {"particles",
         "dBody spheres (scene radius and mass) in a dSimpleSpace; planes as plane geoms; only "
         "plane-sphere "
         "pairs tested (dSpaceCollide2); drag, wind, attractors as dBodyAddForce each step",
         "model only what the scene needs: no particle-particle contact"},
        {"contacts",
         "one dHashSpace of geoms (statics without a body, planes as plane geoms); up to 8 "
         "points per pair, a contact joint each",
         "ODE needs a joint per contact point; 8 is as many as its box-box clip gives"},
        {"contact surface",
         "dContactApprox1 (friction pyramid, limit μ × normal force) with μ = √(μa μb); "
         "dContactBounce with bounce = max(ea, eb), bounce_vel 0.1 m/s",
         "the scene's pair rule and restitution threshold; without Approx1 ODE's mu is a fixed "
         "force limit, not Coulomb"},
        {"ERP / CFM", "world defaults: ERP 0.2, CFM 1e-10 (double); no soft contact",
         "ODE's own defaults, stated; contact surface layer 0 and max correcting velocity "
         "infinite (defaults)"},
        {"dWorldStep on contacts", "only up to 20 dynamic bodies (else unsupported)",
         "its direct solve is O(rows³) per island"},
        {"message handler", "ODE's messages recorded; any message during a step ends the run "
         "as an error",
         "dWorldStep reports 'LCP internal error' on degenerate contact sets and carries on "
         "with a wrong answer (a 10-box tower fell through itself)"},
        {"particle contacts",
         "dContactBounce, bounce = restitution, bounce_vel 0, Coulomb mu = friction",
         "ODE's friction is Coulomb; the scene's (and rtp's) removes a fraction of tangential "
         "velocity"},
        variant == "step-joint"
            ? Setting{"springs", "DBall joint with ERP = hk/(hk+c), CFM = 1/(hk+c)",
                      "ODE's native spring: a soft distance constraint, implicit"}
            : Setting{"springs", "external force (dBodyAddForceAtPos), once per step",
                      "the scene's spring law from the state at the start of the step"},
    };
  };
  state_instruction_set(info, "x86-64 baseline: SSE2 (Debian's libode, generic build)",
                        "Debian builds for the architecture's baseline; rtp's -x86-64 variants "
                        "are the equal-instruction-set comparison");
  return info;
}

}  // namespace physbench
