// MuJoCo adapter (2.2.2). The scene becomes an MJCF model held in memory (a virtual file):
// one free-jointed body per dynamic scene body, mass properties given explicitly. MuJoCo's
// "up" is only its default gravity; the scene's gravity vector is passed as it is.
//
// A free joint's qvel holds the linear velocity in the world frame and the angular velocity
// in the body frame: the adapter converts both ways.
#include <mujoco/mujoco.h>

#include <cstring>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "physbench/registry.h"
#include "physbench/springs.h"

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
  return "Euler";
}

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
    const std::string a = "s" + std::to_string(i) + "a", b = "s" + std::to_string(i) + "b";
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
      << "\" integrator=\"" << integrator_name(variant) << "\">\n";
  // a scene without collisions runs no collision detection at all
  if (!scene.collisions) xml << "    <flag contact=\"disable\"/>\n";
  xml << "  </option>\n  <worldbody>\n";
  for (const std::string& s : world_sites) xml << "    " << s << "\n";
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
      xml << "      <geom type=\"box\" size=\"" << triple(b.shape.half_extents) << "\"/>\n";
    else
      xml << "      <geom type=\"sphere\" size=\"" << b.shape.radius << "\"/>\n";
    for (const std::string& s : body_sites[i]) xml << "      " << s << "\n";
    xml << "    </body>\n";
  }
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
  ~MujocoEngine() override {
    if (data_) mj_deleteData(data_);
    if (model_) mj_deleteModel(model_);
  }

  void load(const Scene& scene) override {
    scene_ = scene;
    const std::string xml = model_xml(scene, variant_);
    // mjVFS is about 2 MB: on the heap
    auto vfs = std::make_unique<mjVFS>();
    mj_defaultVFS(vfs.get());
    if (mj_makeEmptyFileVFS(vfs.get(), "scene.xml", static_cast<int>(xml.size())) != 0)
      throw std::runtime_error("mujoco: cannot create the in-memory model file");
    const int file = mj_findFileVFS(vfs.get(), "scene.xml");
    std::memcpy(vfs->filedata[file], xml.data(), xml.size());
    char error[1000] = "";
    model_ = mj_loadXML("scene.xml", vfs.get(), error, sizeof error);
    mj_deleteVFS(vfs.get());
    if (!model_) throw std::runtime_error(std::string("mujoco: model rejected: ") + error);
    data_ = mj_makeData(model_);

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
    mj_forward(model_, data_);
  }

  void step() override { mj_step(model_, data_); }

  // the velocity change, written into the free joint's qvel (angular part in the body frame)
  void apply_impulse(int b, const Vec3& impulse, const Vec3& point) override {
    const BodyState now = body_state(b);
    const VelocityChange change = impulse_velocity_change(scene_.bodies[b], now, impulse, point);
    const Vec3 local_angular = now.orientation.conjugate() * change.angular;
    mjtNum* v = data_->qvel + model_->jnt_dofadr[model_->body_jntadr[body_of_[b]]];
    for (int k = 0; k < 3; ++k) {
      v[k] += change.linear[k];
      v[3 + k] += local_angular[k];
    }
  }

  BodyState body_state(int index) const override {
    const int body = body_of_[index];
    if (body < 0)
      return {scene_.bodies[index].position, scene_.bodies[index].orientation, Vec3::Zero(),
              Vec3::Zero()};
    const int joint = model_->body_jntadr[body];
    const mjtNum* q = data_->qpos + model_->jnt_qposadr[joint];
    const mjtNum* v = data_->qvel + model_->jnt_dofadr[joint];
    BodyState s;
    s.position = Vec3(q[0], q[1], q[2]);
    s.orientation = Quat(q[3], q[4], q[5], q[6]).normalized();
    s.linear_velocity = Vec3(v[0], v[1], v[2]);
    s.angular_velocity = s.orientation * Vec3(v[3], v[4], v[5]);
    return s;
  }

 private:
  std::string variant_;
  Scene scene_;
  mjModel* model_ = nullptr;
  mjData* data_ = nullptr;
  std::vector<int> body_of_;  // scene body → MuJoCo body id, -1 for static
};

}  // namespace

EngineInfo mujoco_engine_info() {
  EngineInfo info;
  info.name = "mujoco";
  info.variants = {"euler", "rk4", "implicit"};
  info.version = mj_versionString();
  info.unsupported = [](const Scene& scene, const std::string&) -> std::optional<std::string> {
    if (scene.particles) return "particle sets are not mapped onto MuJoCo yet";
    if (scene.has_contacts())
      return "contact scenes are not mapped onto MuJoCo yet (nconmax/njmax are not sized from the "
             "scene)";
    return std::nullopt;
  };
  info.create = [](const std::string& variant) -> std::unique_ptr<Engine> {
    return std::make_unique<MujocoEngine>(variant);
  };
  info.settings = [](const std::string& variant) {
    return std::vector<Setting>{
        {"integrator", integrator_name(variant), "the variant"},
        {"contact flag", "disabled when the scene has collisions off",
         "model only what the scene needs"},
        {"mass properties", "explicit <inertial> from the scene", "same inertia in every engine"},
        {"joint", "one free joint per dynamic body", "a free rigid body, as in every engine"},
        {"springs",
         "spatial tendon between two sites (stiffness, damping, springlength from the scene)",
         "MuJoCo's passive spring force, the scene's law, evaluated at every integrator stage"},
    };
  };
  return info;
}

}  // namespace physbench
