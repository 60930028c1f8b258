// A scene is data: what exists and what to record, nothing about any engine.
//
// World convention: metres, kilograms, seconds; y is up (gravity is a free vector, so an
// engine with another "up" needs only the vector); a planar scene moves in the XY plane and
// rotates about z only. Angular velocities are in the world frame. Every adapter consumes
// this same structure; built-in scenarios create it in C++ and scene files in JSON.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace physbench {

using Vec3 = Eigen::Vector3d;
using Quat = Eigen::Quaterniond;
using Mat3 = Eigen::Matrix3d;

enum class ShapeKind { Box, Sphere, Plane };

struct Shape {
  ShapeKind kind = ShapeKind::Box;
  Vec3 half_extents = Vec3(0.5, 0.5, 0.5);  // box (m)
  double radius = 0.5;                      // sphere (m)
  // a plane is the body's local y = 0 surface, solid below; it must be static
};

struct BodySpec {
  std::string name;
  Shape shape;
  double mass = 1.0;                     // kg; 0 = static
  Vec3 position = Vec3::Zero();          // centre of mass, world (m)
  Quat orientation = Quat::Identity();   // body to world
  Vec3 linear_velocity = Vec3::Zero();   // world (m/s)
  Vec3 angular_velocity = Vec3::Zero();  // world (rad/s)
  // the body's material; a pair of bodies touches with friction √(μa μb) and restitution
  // max(ea, eb) (pair_friction, pair_restitution), and every adapter maps to that
  double friction = 0.5;     // Coulomb coefficient
  double restitution = 0.0;  // 0..1
};

// Hooke spring plus damping between a body point and a world point or another body's point
struct SpringSpec {
  int body_a = 0;
  Vec3 local_point_a = Vec3::Zero();  // body-a frame (m)
  int body_b = -1;                    // -1: point_b is a world anchor
  Vec3 point_b = Vec3::Zero();        // body-b frame, or world (m)
  double stiffness = 0.0;             // N/m
  double damping = 0.0;               // N s/m
  double rest_length = 0.0;           // m
};

// an impulse at a world point at a given time: the seed's keyboard pushes, scheduled
struct ImpulseSpec {
  double time = 0.0;  // s; applied before the step that starts at round(time / dt)
  int body = 0;
  Vec3 impulse = Vec3::Zero();  // N s, world
  Vec3 point = Vec3::Zero();    // world point of application (m)
};

// A set of particles: point masses under gravity, attractors, drag and wind, colliding with
// planes and nothing else (no particle–particle contact in any engine). Particle i is probed as
// body index bodies.size() + i.
struct ParticleAttractor {
  Vec3 position = Vec3::Zero();  // m
  double strength = 0.0;         // m³/s²: a = s r / (|r|² + ε²)^{3/2}; negative repels
};

struct ParticlePlaneSpec {
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitY();  // unit; particles stay on this side
};

struct ParticleSetSpec {
  long count = 0;
  Vec3 spawn_min = Vec3::Zero(), spawn_max = Vec3::Zero();  // uniform initial positions (m)
  Vec3 velocity_min = Vec3::Zero(),
       velocity_max = Vec3::Zero();  // uniform initial velocities (m/s)
  double mass = 0.001;               // kg per particle
  double radius = 0.01;              // m: the sphere an engine without point particles uses
  double drag = 0.0;                 // 1/s: a += drag (wind + offset − v)
  Vec3 wind = Vec3::Zero();          // m/s
  double wind_jitter = 0.0;          // m/s: per-particle uniform offset, seeded
  std::vector<ParticleAttractor> attractors;
  double softening = 0.05;  // ε (m)
  std::vector<ParticlePlaneSpec> planes;
  double restitution = 0.5;  // normal velocity kept on a bounce
  double friction = 0.0;     // fraction of tangential velocity lost on a bounce, 0..1
  double lifetime = 0.0;     // s; > 0: particles age and are re-emitted from the spawn box
  std::uint64_t seed = 1;
  std::vector<long> probe = {0};  // particles to record
};

// what the harness compares each engine's trajectory with
enum class ReferenceKind {
  None,        // invariants only (energy, momenta)
  Ballistic,   // closed-form free flight: x0 + v0 t + ½ g t² for every centre of mass, and the
               // torque-free rotation of bodies with two equal principal moments (symmetric tops)
  Oscillator,  // closed form of one body on one spring to a world anchor, moving along the spring
  Orbit,       // closed form of one particle on a circular orbit about one attractor
  Bounce,      // closed form of one particle dropped from rest onto one plane with restitution
  Converged,   // SciPy's DOP853 at rtol 1e-12, shown converged against rtol 1e-13
};

// What a scene asks to be measured. The contact metrics (docs/metrics.md) are computed from the
// sampled poses the same way for every engine:
//   StackDrift    largest horizontal displacement of any dynamic body from its start, the top
//                 body's height change, speeds at rest
//   Penetration   deepest overlap of any two bodies' true shapes, by rtp's narrow phase
//   BounceApex    one body dropped on a plane: apex heights against e^(2n) h0
//   Incline       one body on a sloped plane: slide and acceleration against g (sin θ − μ cos θ)
//   Exchange      two bodies in a head-on collision: final velocities against the 1D closed form
//   Tunnelling    one fast body at a static wall: did it end up beyond the wall?
//   Confined      dynamic bodies in a container of static world-aligned boxes on a plane: how
//                 many end outside it or above its rim?
enum class Metric {
  Position,
  Orientation,
  Energy,
  LinearMomentum,
  AngularMomentum,
  StackDrift,
  Penetration,
  BounceApex,
  Incline,
  Exchange,
  Tunnelling,
  Confined,
  Rolling,
  Elastic,
};

// every metric, in declaration order (for parsing and messages)
const std::vector<Metric>& all_metrics();

struct Probe {
  std::vector<int> bodies;       // empty: every dynamic body
  double interval = 1.0 / 60.0;  // s between samples (rounded to whole steps)
  std::vector<Metric> metrics = {Metric::Position};
};

struct Reference {
  ReferenceKind kind = ReferenceKind::None;
  int dt_divisor = 64;  // an earlier rtp-computed reference's step divisor: read, not used
};

struct Scene {
  std::string name;
  std::string description;
  Vec3 gravity = Vec3(0.0, -9.81, 0.0);  // m/s²
  double dt = 1.0 / 60.0;                // fixed step (s)
  double duration = 2.0;                 // simulated time (s)
  bool planar = false;                   // all motion in the XY plane: 2D engines may run it
  bool collisions = true;                // false: bodies pass through each other and planes
  std::vector<BodySpec> bodies;
  std::vector<SpringSpec> springs;
  std::vector<ImpulseSpec> impulses;
  std::optional<ParticleSetSpec> particles;
  Probe probe;
  Reference reference;

  long step_count() const;                 // duration / dt, rounded
  bool has_contacts() const;               // collisions on and at least two bodies that could touch
  int probe_every_steps() const;           // interval / dt, rounded, at least 1
  std::vector<int> probed_bodies() const;  // probe.bodies, or every dynamic body
};

// the pair rule for two materials: friction √(μa μb), restitution max(ea, eb)
double pair_friction(const BodySpec& a, const BodySpec& b);
double pair_restitution(const BodySpec& a, const BodySpec& b);

// restitution applies to impacts faster than this normal speed; slower contacts are inelastic, so
// resting bodies do not jitter. Engines that have such a threshold get this one (m/s).
inline constexpr double kRestitutionThreshold = 0.1;

// mass properties of a shape of the given mass: principal inertia in the body frame (kg m²)
Vec3 principal_inertia(const Shape& shape, double mass);

// the body axis (0, 1, 2) of a symmetric top — the one whose moment differs from the two equal
// others, any axis when all three are equal — or nullopt when all three differ
std::optional<int> symmetry_axis(const Vec3& principal_inertia);

// The scene format's version and its caps (docs/scene-format.md gives each one's reason). A cap
// bounds what one scene can ask of the harness: memory, time or file size; ranges keep every value
// where the engines' double or float arithmetic means something.
inline constexpr int kSceneFormatVersion = 1;
namespace limits {
inline constexpr std::uintmax_t kFileBytes = 64u << 20;  // a scene file, bytes
inline constexpr int kNestingDepth = 16;                 // JSON arrays and objects inside each other
inline constexpr std::size_t kNameLength = 100;          // scene and body names, bytes
inline constexpr std::size_t kDescriptionLength = 10000; // bytes
inline constexpr double kMinDt = 1e-7, kMaxDt = 1.0;     // s
inline constexpr double kMaxDuration = 3600.0;           // s
inline constexpr long kMaxSteps = 100'000'000;           // duration / dt
inline constexpr std::size_t kMaxBodies = 50'000;
inline constexpr std::size_t kMaxSprings = 50'000;
inline constexpr std::size_t kMaxImpulses = 100'000;
inline constexpr long kMaxParticles = 10'000'000;
inline constexpr std::size_t kMaxAttractors = 1'000;
inline constexpr std::size_t kMaxParticlePlanes = 1'000;
inline constexpr long kMaxProbeSamples = 10'000'000;     // samples x probed bodies and particles
inline constexpr int kMaxDtDivisor = 1'024;
inline constexpr double kMaxCoordinate = 1e6;            // m, any position or point component
inline constexpr double kMinSize = 1e-4, kMaxSize = 1e4; // m, half extents and radii
inline constexpr double kMinMass = 1e-9, kMaxMass = 1e9; // kg (a dynamic body; 0 is static)
inline constexpr double kMaxSpeed = 1e5;                 // m/s, any velocity component
inline constexpr double kMaxAngularSpeed = 1e5;          // rad/s, any component
inline constexpr double kMaxGravity = 1e4;               // m/s², any component
inline constexpr double kMaxFriction = 10.0;
inline constexpr double kMaxStiffness = 1e12;            // N/m
inline constexpr double kMaxDamping = 1e12;              // N s/m
inline constexpr double kMaxImpulse = 1e9;               // N s, any component
inline constexpr double kMaxAttractorStrength = 1e15;    // m³/s², magnitude
inline constexpr double kMaxDrag = 1e4;                  // 1/s
}  // namespace limits

// Throws SceneError naming the first invalid field ("bodies[2].mass: must be >= 0, got -1").
void validate(const Scene& scene);

struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

const char* to_string(ShapeKind kind);
const char* to_string(ReferenceKind kind);
const char* to_string(Metric metric);
std::optional<Metric> metric_from_string(const std::string& name);

}  // namespace physbench
