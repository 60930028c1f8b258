// MuJoCo adapter, built twice: against Debian's 2.2.2 (in physbench) and against MuJoCo 4 from
// the mujoco-core wheel (in physbench-mujoco4; the two export the same symbols). The code is
// one; `#if mjVERSION_HEADER` marks only where the API or the defaults changed. The scene
// becomes an MJCF model held in memory (a virtual file): one free-jointed body per dynamic scene
// body, mass properties given explicitly. MuJoCo's "up" is only its default gravity; the
// scene's gravity vector is passed as it is.
//
// A free joint's qvel holds the linear velocity in the world frame and the angular velocity
// in the body frame: the adapter converts both ways.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "physbench/mujoco_buffers.h"
#include "physbench/particle_driver.h"
#include "physbench/registry.h"
#include "physbench/springs.h"

#ifndef PHYSBENCH_MUJOCO_NAME
#define PHYSBENCH_MUJOCO_NAME "mujoco"
#endif

// MuJoCo 3.0 replaced nconmax/njmax (fixed buffers) with one arena for contacts, constraints
// and the stack (`<size memory>`), and the file-based VFS calls with mj_addBufferVFS
#define PHYSBENCH_MUJOCO_ARENA (mjVERSION_HEADER >= 300)

namespace physbench {

namespace {

std::string triple(const Vec3& v) {
  std::ostringstream out;
  out << std::setprecision(17) << v.x() << ' ' << v.y() << ' ' << v.z();
  return out.str();
}

std::string quaternion(const Quat& q) {
  std::ostringstream out;
  out << std::setprecision(17) << q.w() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z();
  return out.str();
}

const char* integrator_name(const std::string& variant) {
  if (variant == "rk4") return "RK4";
  if (variant == "implicit") return "implicit";
  if (variant == "implicitfast") return "implicitfast";
  return "Euler";
}

// the largest particle set run as MuJoCo bodies (measured: 1,000 load and step; 3,000 do not)
constexpr long kMaxMujocoParticles = 1000;

// The contact damping ratio ζ whose bounce keeps the fraction e of the normal speed: a damped
// oscillator's half period ends at e = exp(−πζ / √(1 − ζ²)); e = 0 is critical damping.
double damping_ratio_for_restitution(double e) {
  if (e <= 0.0) return 1.0;
  const double log_e = std::log(std::min(e, 0.999));
  return -log_e / std::sqrt(std::numbers::pi * std::numbers::pi + log_e * log_e);
}

// Particles: a free body with a sphere geom each (the scene's radius and mass) and the planes as
// infinite plane geoms of the world. contype/conaffinity let a particle touch planes only: a
// particle has contype 2, conaffinity 0; a plane contype 0, conaffinity 2 (a contact needs
// contype & conaffinity nonzero one way or the other). Drag, wind and attractors are applied by
// the adapter as a passive force (MujocoEngine::particle_forces).
void particles_xml(const Scene& scene, std::ostringstream& xml) {
  const ParticleSetSpec& p = *scene.particles;
  const double dt = scene.dt;
  // MuJoCo's contacts are soft: a spring-damper with the damping ratio that gives the scene's
  // restitution; Coulomb friction μ = the scene's friction fraction, as in ODE (condim 1 when
  // there is none: a zero-width friction pyramid is degenerate).
  // Its natural frequency is 1 / (timeconst · dampratio): the
  // time constant is 2 dt / ζ, so that frequency stays at 1 / (2 dt) whatever ζ (with 2 dt at
  // small ζ the spring was so stiff that a 0.8 bounce launched the particle at 125 m/s)
  const double zeta = damping_ratio_for_restitution(p.restitution);
  std::ostringstream attributes;
  attributes << std::setprecision(17) << "solref=\"" << 2.0 * dt / zeta << ' ' << zeta
             << "\" friction=\"" << p.friction << " 0.005 0.0001\" condim=\""
             << (p.friction > 0.0 ? 3 : 1) << "\"";
  const std::string contact = attributes.str();
  for (const ParticlePlaneSpec& plane : p.planes)
    xml << "    <geom type=\"plane\" size=\"0 0 1\" pos=\"" << triple(plane.point) << "\" zaxis=\""
        << triple(plane.normal) << "\" contype=\"0\" conaffinity=\"2\" " << contact << "/>\n";
  // placed at the origin here: load() sets each start from the particle driver
  for (long i = 0; i < p.count; ++i)
    xml << "    <body name=\"p" << i << "\"><freejoint/><geom type=\"sphere\" size=\"" << p.radius
        << "\" mass=\"" << p.mass << "\" contype=\"2\" conaffinity=\"0\" " << contact
        << "/></body>\n";
}

// ---- contact scenes ----

// the body's bounding box in the world (a plane has none: it is handled apart)
void bounds_of(const BodySpec& b, Vec3& low, Vec3& high) {
  const Vec3 reach = b.shape.kind == ShapeKind::Box
                         ? Vec3(b.orientation.toRotationMatrix().cwiseAbs() * b.shape.half_extents)
                         : Vec3::Constant(b.shape.radius);
  low = b.position - reach;
  high = b.position + reach;
}

// contact points MuJoCo 2.2 makes for a pair at rest: a box face on a box face or on a plane
// gives 4, a sphere 1
int contacts_per_pair(const BodySpec& a, const BodySpec& b) {
  return a.shape.kind == ShapeKind::Sphere || b.shape.kind == ShapeKind::Sphere ? 1 : 4;
}

// the largest njmax this adapter asks for: MuJoCo 2.2.2's mjData holds efc_AR, njmax × njmax
// doubles, whatever the solver (12,000 rows: 1.1 GB; at 16,000 rows mj_makeData failed here)
constexpr long kMaxConstraintRows = 12000;
// the largest arena this adapter asks MuJoCo 4 for (the machines have 24 GB, shared)
constexpr double kMaxArenaBytes = 4.0 * (1L << 30);
// the rk4 and implicit variants on contact scenes up to this many bodies (their cost)
constexpr int kMaxBodiesForCostlyVariants = 60;

bool uniform_materials(const Scene& scene) {
  for (const BodySpec& b : scene.bodies)
    if (b.friction != scene.bodies[0].friction || b.restitution != scene.bodies[0].restitution)
      return false;
  return true;
}

// the contact attributes every geom of a contact scene carries: Coulomb μ (condim 3, or 1 when
// frictionless), and for a restitution e > 0 the spring-damper that keeps the fraction e of the
// normal speed (as for particles); e = 0 keeps MuJoCo's default solref (0.02 s, 1) and solimp
std::string contact_attributes(const Scene& scene) {
  const BodySpec& material = scene.bodies.front();
  std::ostringstream out;
  out << std::setprecision(17) << " friction=\"" << material.friction << " 0.005 0.0001\" condim=\""
      << (material.friction > 0.0 ? 3 : 1) << "\"";
  if (material.restitution > 0.0) {
    const double zeta = damping_ratio_for_restitution(material.restitution);
    out << " solref=\"" << 2.0 * scene.dt / zeta << ' ' << zeta << "\"";
  }
  return out.str();
}

int dynamic_bodies(const Scene& scene) {
  int dynamic = 0;
  for (const BodySpec& b : scene.bodies) dynamic += b.mass > 0.0;
  return dynamic;
}

#if PHYSBENCH_MUJOCO_ARENA
// MuJoCo 4's arena for a contact scene. Its contacts: 2.2.2's count, but at least 12 per
// dynamic body (a box on three others, 4 points each), so a pile that forms during the run fits
// (2.2.2's njmax² matrix made that unaffordable there). Per contact its record, per constraint
// row its vectors and its Jacobian row (dense below 60 degrees of freedom, MuJoCo's automatic
// choice, else sparse), for PGS its row of the dual matrix, and the stack, all doubled; too small
// an arena drops contacts, which the adapter reports as an error
double mujoco_arena_bytes(const Scene& scene, const MujocoBuffers& buffers,
                          const std::string& variant) {
  const double nv = 6.0 * dynamic_bodies(scene);
  const double contacts = std::max(double(buffers.nconmax), 12.0 * dynamic_bodies(scene));
  const double rows = contacts * double(buffers.njmax) / double(std::max(1L, buffers.nconmax));
  const double jacobian_row = nv < 60 ? nv : 2.0 * 12.0;
  const double dual_row = variant == "pgs-10" ? (nv < 60 ? rows : 2.0 * 48.0) : 0.0;
  const double bytes = contacts * 1024.0 + rows * 8.0 * (64.0 + 3.0 * jacobian_row + dual_row) +
                       nv * 8.0 * 64.0;
  return 2.0 * bytes + double(16 << 20);
}
#endif

}  // namespace

MujocoBuffers mujoco_buffers(const Scene& scene) {
  MujocoBuffers buffers;
  if (!scene.has_contacts()) return buffers;
  // pairs that touch at the start or can meet: bounding boxes within 5 cm, grown by what the two
  // bodies' starting speeds cover in the scene's duration; every dynamic body with every plane.
  // A contact set that grows beyond this (a collapse, a pile) overflows and is reported.
  constexpr double kGap = 0.05;
  const std::size_t n = scene.bodies.size();
  std::vector<Vec3> low(n), high(n);
  for (std::size_t i = 0; i < n; ++i)
    if (scene.bodies[i].shape.kind != ShapeKind::Plane) bounds_of(scene.bodies[i], low[i], high[i]);
  std::vector<std::size_t> order;
  long contacts = 0;
  std::vector<bool> has_neighbour(n, false);
  for (std::size_t i = 0; i < n; ++i)
    if (scene.bodies[i].shape.kind != ShapeKind::Plane) order.push_back(i);
  double fastest = 0.0;
  for (const BodySpec& b : scene.bodies) fastest = std::max(fastest, b.linear_velocity.norm());
  const double reach = kGap + 2.0 * fastest * scene.duration;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return low[a].x() < low[b].x(); });
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t i = order[k];
    for (std::size_t m = k + 1; m < order.size() && low[order[m]].x() <= high[i].x() + reach; ++m) {
      const std::size_t j = order[m];
      const BodySpec& a = scene.bodies[i];
      const BodySpec& b = scene.bodies[j];
      if (a.mass == 0.0 && b.mass == 0.0) continue;
      const double grow = (a.linear_velocity.norm() + b.linear_velocity.norm()) * scene.duration +
                          kGap;
      bool apart = false;
      for (int axis = 0; axis < 3; ++axis)
        apart = apart || low[j][axis] > high[i][axis] + grow || low[i][axis] > high[j][axis] + grow;
      if (!apart) {
        contacts += contacts_per_pair(a, b);
        has_neighbour[i] = has_neighbour[j] = true;
      }
    }
  }
  // a plane, for each dynamic body near it or with nothing else near it (a body dropped onto
  // it): a box high in a pyramid meets the ground only if the pyramid falls, which overflows
  for (std::size_t i : order) {
    const BodySpec& a = scene.bodies[i];
    if (a.mass == 0.0) continue;
    for (const BodySpec& p : scene.bodies) {
      if (p.shape.kind != ShapeKind::Plane) continue;
      const Vec3 normal = p.orientation * Vec3::UnitY();
      const double lowest = (a.position - p.position).dot(normal) -
                            (a.shape.kind == ShapeKind::Box
                                 ? (a.orientation.conjugate() * normal).cwiseAbs().dot(
                                       a.shape.half_extents)
                                 : a.shape.radius);
      if (lowest <= reach || !has_neighbour[i]) contacts += contacts_per_pair(a, p);
    }
  }
  // headroom for a contact or two that flickers in and out
  buffers.nconmax = contacts + contacts / 4 + 8;
  const int rows_per_contact = scene.bodies.front().friction > 0.0 ? 4 : 1;  // pyramidal, condim 3
  buffers.njmax = rows_per_contact * buffers.nconmax;
  return buffers;
}

namespace {

// A spring is a spatial tendon between two sites, with the scene's stiffness, damping and rest
// length: MuJoCo's own passive force, Hooke plus damping along the line — the scene's law —
// evaluated at every integrator stage. (An external force held through RK4's four stages would
// make the spring explicit Euler: its energy grew 32-fold on spring-oscillator.)
std::string model_xml(const Scene& scene, const std::string& variant) {
  // sites: per dynamic body its attachment points; world sites for anchors and static ends
  std::vector<std::vector<std::string>> body_sites(scene.bodies.size());
  std::vector<std::string> world_sites;
  auto site = [](const std::string& name, const Vec3& pos) {
    return "<site name=\"" + name + "\" pos=\"" + triple(pos) + "\" size=\"0.01\"/>";
  };
  for (std::size_t i = 0; i < scene.springs.size(); ++i) {
    const SpringSpec& s = scene.springs[i];
    const std::string index = std::to_string(i), a = "s" + index + "a", b = "s" + index + "b";
    const BodySpec& body_a = scene.bodies[s.body_a];
    if (body_a.mass > 0.0)
      body_sites[s.body_a].push_back(site(a, s.local_point_a));
    else
      world_sites.push_back(site(a, body_a.position + body_a.orientation * s.local_point_a));
    if (s.body_b < 0) {
      world_sites.push_back(site(b, s.point_b));
    } else {
      const BodySpec& body_b = scene.bodies[s.body_b];
      if (body_b.mass > 0.0)
        body_sites[s.body_b].push_back(site(b, s.point_b));
      else
        world_sites.push_back(site(b, body_b.position + body_b.orientation * s.point_b));
    }
  }

  std::ostringstream xml;
  xml << std::setprecision(17);
  xml << "<mujoco model=\"physbench\">\n";
  xml << "  <option timestep=\"" << scene.dt << "\" gravity=\"" << triple(scene.gravity)
      << "\" integrator=\"" << integrator_name(variant) << "\""
      << (scene.particles ? " jacobian=\"sparse\"" : "")
      << (variant == "pgs-10" ? " solver=\"PGS\" iterations=\"10\"" : "") << ">\n";
  // a scene without collisions runs no collision detection at all
  if (!scene.collisions) xml << "    <flag contact=\"disable\"/>\n";
  xml << "  </option>\n";
  // room for two contacts per particle (MuJoCo 2.2 sizes its buffers from these; a pyramidal
  // contact of dimension 3 takes 4 constraint rows), and sparse Jacobians: a dense one is
  // constraint rows × 6 particles doubles
  if (scene.particles) {
    const long contacts = 2 * scene.particles->count + 8;
    xml << "  <size nconmax=\"" << contacts << "\" njmax=\"" << 4 * contacts << "\"/>\n";
  }
  const bool contacts = scene.has_contacts();
  const std::string material = contacts ? contact_attributes(scene) : std::string();
  if (contacts) {
    const MujocoBuffers buffers = mujoco_buffers(scene);
#if PHYSBENCH_MUJOCO_ARENA
    // nconmax is legacy and still caps the contact list: left at its default (no cap); the arena
    // holds contacts and constraints
    xml << "  <size memory=\"" << std::llround(mujoco_arena_bytes(scene, buffers, variant))
        << "\"/>\n";
#else
    xml << "  <size nconmax=\"" << buffers.nconmax << "\" njmax=\"" << buffers.njmax << "\"/>\n";
#endif
  }
  xml << "  <worldbody>\n";
  for (const std::string& s : world_sites) xml << "    " << s << "\n";
  // static bodies of a contact scene: world geoms (a plane's normal is its local y)
  for (const BodySpec& b : scene.bodies) {
    if (b.mass > 0.0 || !contacts) continue;
    if (b.shape.kind == ShapeKind::Plane)
      xml << "    <geom type=\"plane\" size=\"0 0 1\" pos=\"" << triple(b.position)
          << "\" zaxis=\"" << triple(b.orientation * Vec3::UnitY()) << "\"" << material << "/>\n";
    else if (b.shape.kind == ShapeKind::Box)
      xml << "    <geom type=\"box\" size=\"" << triple(b.shape.half_extents) << "\" pos=\""
          << triple(b.position) << "\" quat=\"" << quaternion(b.orientation) << "\"" << material
          << "/>\n";
    else
      xml << "    <geom type=\"sphere\" size=\"" << b.shape.radius << "\" pos=\""
          << triple(b.position) << "\"" << material << "/>\n";
  }
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const BodySpec& b = scene.bodies[i];
    if (b.mass == 0.0) continue;  // static geometry arrives with contact scenes
    const Vec3 inertia = principal_inertia(b.shape, b.mass);
    xml << "    <body name=\"b" << i << "\" pos=\"" << triple(b.position) << "\" quat=\""
        << quaternion(b.orientation) << "\">\n";
    xml << "      <freejoint/>\n";
    xml << "      <inertial pos=\"0 0 0\" mass=\"" << b.mass << "\" diaginertia=\""
        << triple(inertia) << "\"/>\n";
    if (b.shape.kind == ShapeKind::Box)
      xml << "      <geom type=\"box\" size=\"" << triple(b.shape.half_extents) << "\"" << material
          << "/>\n";
    else
      xml << "      <geom type=\"sphere\" size=\"" << b.shape.radius << "\"" << material << "/>\n";
    for (const std::string& s : body_sites[i]) xml << "      " << s << "\n";
    xml << "    </body>\n";
  }
  if (scene.particles) particles_xml(scene, xml);
  xml << "  </worldbody>\n";
  if (!scene.springs.empty()) {
    xml << "  <tendon>\n";
    for (std::size_t i = 0; i < scene.springs.size(); ++i) {
      const SpringSpec& s = scene.springs[i];
      xml << "    <spatial stiffness=\"" << s.stiffness << "\" damping=\"" << s.damping
          << "\" springlength=\"" << s.rest_length << "\">\n";
      xml << "      <site site=\"s" << i << "a\"/>\n      <site site=\"s" << i
          << "b\"/>\n    </spatial>\n";
    }
    xml << "  </tendon>\n";
  }
  xml << "</mujoco>\n";
  return xml.str();
}

class MujocoEngine final : public Engine {
 public:
  explicit MujocoEngine(std::string variant) : variant_(std::move(variant)) {}

  // iterations: mjOption::iterations, the solver's iteration cap (its tolerance still ends it
  // early); substeps: mjOption::timestep dt/N and N calls of mj_step (MuJoCo's own way to step
  // finer; the contacts' solref, set from the scene's dt, keeps its time constant)
  Tuning tune(const SolverKnobs& knobs) override {
    Tuning tuning;
    if (knobs.iterations > 0) {
      iterations_ = knobs.iterations;
      const bool pgs = variant_ == "pgs-10";
      tuning.settings.push_back(
          {"solver",
           std::string(pgs ? "PGS" : "Newton") + ", " + std::to_string(knobs.iterations) +
               " iterations" + (pgs ? "" : ", tolerance 1e-8, pyramidal cone"),
           "the sweep's value (--sweep-iterations): mjOption::iterations, a cap the solver's "
           "tolerance may end early"});
    }
    if (knobs.substeps > 0) {
      substeps_ = knobs.substeps;
      tuning.settings.push_back(
          swept_substeps(knobs.substeps, "mjOption::timestep dt/N and N calls of mj_step"));
    }
    return tuning;
  }
  ~MujocoEngine() override {
    if (active_ == this) {
      mjcb_passive = nullptr;
      active_ = nullptr;
    }
    if (data_) mj_deleteData(data_);
    if (model_) mj_deleteModel(model_);
  }

  void load(const Scene& scene) override {
    scene_ = scene;
    contacts_.start(scene);
    const std::string xml = model_xml(scene, variant_);
    // mjVFS is about 2 MB: on the heap
    auto vfs = std::make_unique<mjVFS>();
    mj_defaultVFS(vfs.get());
#if PHYSBENCH_MUJOCO_ARENA
    if (mj_addBufferVFS(vfs.get(), "scene.xml", xml.data(), static_cast<int>(xml.size())) != 0)
      throw std::runtime_error("mujoco: cannot create the in-memory model file");
#else
    if (mj_makeEmptyFileVFS(vfs.get(), "scene.xml", static_cast<int>(xml.size())) != 0)
      throw std::runtime_error("mujoco: cannot create the in-memory model file");
    const int file = mj_findFileVFS(vfs.get(), "scene.xml");
    std::memcpy(vfs->filedata[file], xml.data(), xml.size());
#endif
    char error[1000] = "";
    model_ = mj_loadXML("scene.xml", vfs.get(), error, sizeof error);
    mj_deleteVFS(vfs.get());
    if (!model_) throw std::runtime_error(std::string("mujoco: model rejected: ") + error);
    // a sweep's iterations: the solver's iteration cap (mjOption::iterations; Newton and PGS alike)
    if (iterations_ > 0) model_->opt.iterations = iterations_;
    // a sweep's substeps: the model's step is dt/N, and step() calls mj_step N times
    if (substeps_ > 0) model_->opt.timestep = scene.dt / substeps_;
    data_ = mj_makeData(model_);
    if (!data_)
      throw std::runtime_error("mujoco: mj_makeData failed (nconmax " +
                               std::to_string(model_->nconmax) + ", njmax " +
                               std::to_string(model_->njmax) + ")");

    // the dynamic scene bodies in MuJoCo's body order (body 0 is the world)
    int mujoco_body = 1;
    for (const BodySpec& b : scene.bodies) {
      if (b.mass == 0.0) {
        body_of_.push_back(-1);
        continue;
      }
      body_of_.push_back(mujoco_body++);
    }
    for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
      if (body_of_[i] < 0) continue;
      const BodySpec& b = scene.bodies[i];
      const int dof = model_->jnt_dofadr[model_->body_jntadr[body_of_[i]]];
      const Vec3 local_angular = b.orientation.conjugate() * b.angular_velocity;
      for (int k = 0; k < 3; ++k) {
        data_->qvel[dof + k] = b.linear_velocity[k];
        data_->qvel[dof + 3 + k] = local_angular[k];
      }
    }
    if (scene.particles) {
      driver_ = std::make_unique<ParticleDriver>(scene);
      active_ = this;
      mjcb_passive = &MujocoEngine::particle_forces;
      for (long i = 0; i < driver_->count(); ++i) {
        body_of_.push_back(mujoco_body);
        const rtp::ParticleSpawn start = driver_->start(i);
        set_free_state(mujoco_body++, start.position, start.velocity);
      }
    }
    mj_forward(model_, data_);
  }

  std::optional<ContactCount> contact_count() const override { return contacts_.count(); }

  void step() override {
    for (int k = 0; k < std::max(substeps_, 1); ++k) {
      mj_step(model_, data_);
      // the contacts mj_step's forward pass found and solved (each a point with its own frame)
      if (contacts_.counting()) {
        contacts_.add(data_->ncon);
        contacts_.end_step();
      }
    }
    ++steps_;
    // MuJoCo checks qpos, qvel and qacc each step and, on a non-finite or huge value, warns and
    // resets the state to the model's initial one (mj_resetData) and carries on: the samples then
    // look sane and the run would read as ok. The warning counters are the only trace.
    for (const auto& [warning, what] :
         {std::pair{mjWARN_BADQACC, "bad acceleration (mjWARN_BADQACC)"},
          std::pair{mjWARN_BADQVEL, "bad velocity (mjWARN_BADQVEL)"},
          std::pair{mjWARN_BADQPOS, "bad position (mjWARN_BADQPOS)"}})
      if (data_->warning[warning].number > 0) {
        std::ostringstream why;
        why << "MuJoCo reset its state after its " << what << " warning at step " << steps_
            << " (t = " << steps_ * scene_.dt << " s, degree of freedom "
            << data_->warning[warning].lastinfo << "): the motion is unstable";
        throw EngineExploded(why.str());
      }
    // MuJoCo drops the contacts beyond nconmax (and constraints beyond njmax) and carries on: a
    // run that lost contacts is not a result
    if (data_->warning[mjWARN_CONTACTFULL].number > 0 ||
        data_->warning[mjWARN_CNSTRFULL].number > 0) {
      std::ostringstream why;
#if PHYSBENCH_MUJOCO_ARENA
      why << "MuJoCo's arena overflowed at step " << steps_ << " (memory " << model_->narena
          << " bytes, " << data_->ncon
          << " contacts kept): contacts were dropped, so the run is not a result";
#else
      why << "MuJoCo's contact buffer overflowed at step " << steps_ << " (nconmax "
          << model_->nconmax << ", njmax " << model_->njmax << ", " << data_->ncon
          << " contacts kept): contacts were dropped, so the run is not a result";
#endif
      throw std::runtime_error(why.str());
    }
    if (driver_) {
      const std::size_t first = scene_.bodies.size();
      driver_->age(scene_.dt, [&](long i, const rtp::ParticleSpawn& spawn) {
        set_free_state(body_of_[first + std::size_t(i)], spawn.position, spawn.velocity);
      });
    }
  }

  // Drag, wind and attractors as a passive force: MuJoCo calls mjcb_passive wherever it computes
  // passive forces, so RK4 sees them at every stage (a force held in xfrc_applied through the
  // stages made its orbit first order: 3.3 m off where Euler was 0.07 m). A free joint's first
  // three dofs are world-frame translation, so the force goes straight into qfrc_passive. The
  // callback is global in MuJoCo; each job is one engine in its own process.
  static void particle_forces(const mjModel* m, mjData* d) {
    const MujocoEngine* self = active_;
    if (!self || !self->driver_ || m != self->model_) return;
    const std::size_t first = self->scene_.bodies.size();
    for (long i = 0; i < self->driver_->count(); ++i) {
      const int joint = m->body_jntadr[self->body_of_[first + std::size_t(i)]];
      const mjtNum* q = d->qpos + m->jnt_qposadr[joint];
      const mjtNum* v = d->qvel + m->jnt_dofadr[joint];
      const Vec3 f = self->driver_->force(i, Vec3(q[0], q[1], q[2]), Vec3(v[0], v[1], v[2]));
      mjtNum* passive = d->qfrc_passive + m->jnt_dofadr[joint];
      for (int k = 0; k < 3; ++k) passive[k] += f[k];
    }
  }

  // the velocity change, written into the free joint's qvel (angular part in the body frame)
  void apply_impulse(int b, const Vec3& impulse, const Vec3& point) override {
    const SampledState now = body_state(b);
    const VelocityChange change = impulse_velocity_change(scene_.bodies[b], now, impulse, point);
    const Vec3 local_angular = now.orientation.conjugate() * change.angular;
    mjtNum* v = data_->qvel + model_->jnt_dofadr[model_->body_jntadr[body_of_[b]]];
    for (int k = 0; k < 3; ++k) {
      v[k] += change.linear[k];
      v[3 + k] += local_angular[k];
    }
  }

  SampledState body_state(int index) const override {
    const int body = body_of_[index];
    if (body < 0)
      return {scene_.bodies[index].position, scene_.bodies[index].orientation, Vec3::Zero(),
              Vec3::Zero()};
    const int joint = model_->body_jntadr[body];
    const mjtNum* q = data_->qpos + model_->jnt_qposadr[joint];
    const mjtNum* v = data_->qvel + model_->jnt_dofadr[joint];
    SampledState s;
    s.position = Vec3(q[0], q[1], q[2]);
    s.orientation = Quat(q[3], q[4], q[5], q[6]).normalized();
    s.linear_velocity = Vec3(v[0], v[1], v[2]);
    s.angular_velocity = s.orientation * Vec3(v[3], v[4], v[5]);
    return s;
  }

 private:
  // a free body placed at p, unrotated, moving at v without spin
  void set_free_state(int body, const Vec3& p, const Vec3& v) {
    const int joint = model_->body_jntadr[body];
    mjtNum* q = data_->qpos + model_->jnt_qposadr[joint];
    mjtNum* qv = data_->qvel + model_->jnt_dofadr[joint];
    for (int k = 0; k < 3; ++k) {
      q[k] = p[k];
      qv[k] = v[k];
      qv[3 + k] = 0.0;
    }
    q[3] = 1.0;
    q[4] = q[5] = q[6] = 0.0;
  }

  std::string variant_;
  int iterations_ = 0;  // a sweep's mjOption::iterations; 0: the variant's own
  int substeps_ = 0;    // a sweep's substeps; 0: one mj_step of dt
  Scene scene_;
  std::unique_ptr<ParticleDriver> driver_;
  static inline const MujocoEngine* active_ = nullptr;  // the engine mjcb_passive serves
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::vector<int> body_of_;  // scene body → MuJoCo body id, -1 for static
  long steps_ = 0;
  ContactTally contacts_;
};

}  // namespace

const char* mujoco_engine_name() { return PHYSBENCH_MUJOCO_NAME; }

EngineInfo mujoco_engine_info() {
  EngineInfo info;
  info.name = PHYSBENCH_MUJOCO_NAME;
  info.variants = mujoco_variants(mjVERSION_HEADER);
  info.version = mj_versionString();
  info.unsupported = [](const Scene& scene,
                        const std::string& variant) -> std::optional<std::string> {
    if (auto why = peer_particles_unsupported(scene, "MuJoCo")) return why;
    if (scene.particles && scene.particles->count > kMaxMujocoParticles)
#if PHYSBENCH_MUJOCO_ARENA
      return "over " + std::to_string(kMaxMujocoParticles) +
             " particles not run: the limit measured on MuJoCo 2.2.2 (3,000 free bodies failed to "
             "get an mjData there), not yet measured on MuJoCo 4";
#else
      return "over " + std::to_string(kMaxMujocoParticles) +
             " particles MuJoCo 2.2.2 cannot create its mjData here (3,000 free bodies failed: "
             "its buffers are sized from nv and njmax when the model loads)";
#endif
    if (scene.has_contacts()) {
      const int dynamic = dynamic_bodies(scene);
      if ((variant == "rk4" || variant == "implicit" || variant == "implicitfast") &&
          dynamic > kMaxBodiesForCostlyVariants)
        return "over " + std::to_string(kMaxBodiesForCostlyVariants) +
               " bodies in contact only euler and pgs-10 run: euler took 100 ms per step on the "
               "210-box pyramid, rk4 about 4x that (the suite's time budget)";
      if (!uniform_materials(scene))
        return "MuJoCo combines two geoms' friction by max and solref by mean: the scene's pair "
               "rule holds here only when every body has the same friction and restitution";
      const MujocoBuffers buffers = mujoco_buffers(scene);
#if PHYSBENCH_MUJOCO_ARENA
      const double arena = mujoco_arena_bytes(scene, buffers, variant);
      if (arena > kMaxArenaBytes) {
        std::ostringstream why;
        why << std::setprecision(2) << "the scene needs an arena of about "
            << arena / double(1 << 30) << " GB (this adapter's limit: "
            << kMaxArenaBytes / double(1 << 30) << " GB)";
        return why.str();
      }
#else
      if (buffers.njmax > kMaxConstraintRows) {
        std::ostringstream why;
        why << std::setprecision(2) << "the scene needs about " << buffers.njmax
            << " constraint rows, and MuJoCo 2.2.2's mjData holds an njmax x njmax matrix "
               "(efc_AR): "
            << 8.0 * double(buffers.njmax) * double(buffers.njmax) / double(1 << 30)
            << " GB (this adapter's limit: " << kMaxConstraintRows << " rows)";
        return why.str();
      }
#endif
    }
    return std::nullopt;
  };
  // pgs-10 differs from euler only where there are contacts to solve
  info.applies = [](const Scene& scene, const std::string& variant) {
    return variant != "pgs-10" || scene.has_contacts();
  };
  info.create = [](const std::string& variant) -> std::unique_ptr<Engine> {
    return std::make_unique<MujocoEngine>(variant);
  };
  info.settings = [](const std::string& variant) {
    return std::vector<Setting>{
        {"integrator", integrator_name(variant), "the variant"},
        variant == "pgs-10"
            ? Setting{"solver", "PGS, 10 iterations",
                      "the equal-iterations variant: projected Gauss-Seidel is MuJoCo's nearest to "
                      "10 velocity iterations of sequential impulses"}
            : Setting{"solver", "Newton, 100 iterations, tolerance 1e-8, pyramidal cone "
                      "(MuJoCo's defaults)", "the engine's own defaults"},
#if PHYSBENCH_MUJOCO_ARENA
        {"contact memory", "<size memory> from the scene: contacts counted as for 2.2.2 (4 points "
         "per pair whose bounds lie within 5 cm, grown by the starting speeds over the duration, "
         "and per body and plane where the body is that near the plane or near nothing else, "
         "+25 % + 8, at least 12 per dynamic body; 4 rows each, 1 when frictionless), then per "
         "contact 1 KB, per row its "
         "vectors, Jacobian row (dense under 60 dofs) and for pgs-10 its dual row, doubled, "
         "+16 MB; at most 4 GB; nconmax and njmax not set (legacy)",
         "MuJoCo 4 drops contacts beyond its arena: sized from the scene, and an overflow ends the "
         "run as an error"},
        {"islands, nativeccd, multiccd", "on (MuJoCo 4's defaults: islands since 3.3.6, nativeccd "
         "since 3.3.0, multiccd since 3.8.0)", "the engine's own defaults"},
        {"sleep", "off (MuJoCo 4's default: mjENBL_SLEEP not set)", "sleeping off in every engine"},
#else
        {"contact buffers", "nconmax from the scene: 4 points per pair whose bounds lie within 5 "
         "cm (grown by the starting speeds over the duration), and per body and plane where the "
         "body is that near the plane or near nothing else, +25 % + 8; at most 12,000 rows; "
         "njmax = 4 rows per contact (1 when frictionless)",
         "MuJoCo 2.2.2 drops contacts beyond nconmax silently: sized from the scene, and an "
         "overflow ends the run as an error"},
#endif
        {"contact materials", "friction μ 0.005 0.0001, condim 3 (1 when μ = 0); e > 0: solref = "
         "(2 dt / ζ, ζ), ζ = −ln e / √(π² + ln² e); e = 0: default solref (0.02, 1) and solimp "
         "(0.9, 0.95, 0.001); margin 0",
         "MuJoCo's contact is soft by design; every geom carries the scene's one material, since "
         "MuJoCo combines friction by max"},
        {"static bodies", "world geoms: planes (zaxis = the plane's normal), boxes, spheres",
         "the scene's static geometry"},
        {"contact flag", "disabled when the scene has collisions off",
         "model only what the scene needs"},
        {"mass properties", "explicit <inertial> from the scene", "same inertia in every engine"},
        {"joint", "one free joint per dynamic body", "a free rigid body, as in every engine"},
        {"springs",
         "spatial tendon between two sites (stiffness, damping, springlength from the scene)",
         "MuJoCo's passive spring force, the scene's law, evaluated at every integrator stage"},
        {"particles",
         "free bodies with a sphere geom (scene radius and mass); planes as world plane geoms; "
         "contype/conaffinity so particles touch planes only; drag, wind, attractors as a passive "
         "force (mjcb_passive, so every RK4 stage sees them); sparse Jacobians",
         "model only what the scene needs: no particle-particle contact"},
        {"particle contacts",
         "soft contact: solref = (2 dt / ζ, ζ) with ζ = −ln e / √(π² + ln² e), Coulomb μ = the "
         "scene's friction, condim 3 (1 when frictionless); nconmax = 2 × particles",
         "MuJoCo has no restitution coefficient: a spring-damper contact with this damping ratio "
         "keeps the fraction e of the normal speed; its friction is Coulomb, the scene's a "
         "velocity fraction"},
    };
  };
#if mjVERSION_HEADER >= 4000000
  state_instruction_set(info, "AVX, no FMA (PyPI's mujoco wheel, as built by MuJoCo's release)",
                        "MuJoCo's own build enables AVX on x86-64 (objdump of libmujoco.so: "
                        "ymm registers, no vfmadd)");
#else
  state_instruction_set(info, "x86-64 baseline: SSE2 (Debian's libmujoco, generic build)",
                        "Debian builds for the architecture's baseline; rtp's -x86-64 variants "
                        "are the equal-instruction-set comparison");
#endif
  return info;
}

}  // namespace physbench
