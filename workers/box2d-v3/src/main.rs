//! Box2D v3 (the C library, built from source by boxdd-sys) as a harness worker for planar
//! scenes: docs/worker-protocol.md. Its names collide with Box2D 2.4's, so it lives here, in a
//! process of its own, never beside the in-process 2.4 adapter.

use boxdd_sys::ffi::*;
use physbench_worker::{
    setting, Engine, Knobs, Scene, Setting, Shape, State, World, RESTITUTION_THRESHOLD,
};

struct Box2dV3;

// Box2D v3's default: 4 substeps, each one biased soft solve and one relax pass
const DEFAULT_SUBSTEPS: i32 = 4;
// equal iterations: the substep is v3's iteration (one solve and one relax pass each)
const EQUAL_SUBSTEPS: i32 = 10;
// half length of the segment that stands for a plane (m): no scene reaches its ends
const PLANE_HALF_LENGTH: f32 = 1000.0;
// the scenes' speeds stay below 1e5 m/s (docs/scene-format.md); the default clamp is 400 m/s
const MAXIMUM_LINEAR_SPEED: f32 = 1.0e5;

// built with Box2D's AVX2 path (this package's feature `avx2`)
const AVX2: bool = cfg!(feature = "avx2");

fn substeps(variant: &str) -> i32 {
    if variant == "iterations-10" { EQUAL_SUBSTEPS } else { DEFAULT_SUBSTEPS }
}

fn v2(x: f64, y: f64) -> b2Vec2 {
    b2Vec2 { x: x as f32, y: y as f32 }
}

impl Engine for Box2dV3 {
    fn name(&self) -> &'static str {
        "box2d-v3"
    }
    fn version(&self) -> String {
        // the crate bundles a snapshot of Box2D's main branch (2026-06-16), which already calls
        // itself 3.2.0 though the v3.2.0 release came later: name the commit the build used
        let v = unsafe { b2GetVersion() };
        format!("commit {} (b2GetVersion {}.{}.{}, before the v3.2.0 release; float)",
                &boxdd_sys::UPSTREAM_SHA[..8], v.major, v.minor, v.revision)
    }
    fn variants(&self) -> &'static [&'static str] {
        // the build with Box2D's AVX2 path (feature `avx2`, physbench-box2d-v3-avx2) runs the
        // defaults under a name that says so, beside the SSE2 build's variants
        if AVX2 { &["default-avx2"] } else { &["default", "iterations-10"] }
    }
    fn settings(&self, variant: &str) -> Vec<Setting> {
        let mut s = vec![
            setting("enableSleep", "false (world and every body)", "sleeping off in every engine"),
            setting("restitutionThreshold", RESTITUTION_THRESHOLD,
                    "the scene's 0.1 m/s (default 1 m/s)"),
            setting("maximumLinearSpeed", MAXIMUM_LINEAR_SPEED,
                    "default 400 m/s would clamp a fast body silently; the scene format allows 1e5"),
            setting("mass data", "b2Body_SetMassData from the scene (Iz of the 3D body)",
                    "every engine integrates the same body; shapes at density 0"),
            setting("friction / restitution mixing", "Box2D's own √(μa μb) and max(ea, eb)",
                    "already the scene's pair rule"),
            setting("plane", "a two-sided segment ±1 km along the body's local x axis",
                    "no skin in v3: the segment is the plane's surface itself"),
            setting("polygon radius", "0 (b2MakeBox)",
                    "v3 has no polygon skin: boxes are the scene's exact size"),
            setting("springs", "external force at the attachment points, from the state at the \
                     start of each step", "the same method as the other peers' springs"),
            if AVX2 {
                setting("instruction set", "float, AVX2 (the crate's simd-avx2 feature: BOX2D_AVX2, \
                         -mavx2), -O2, NDEBUG",
                        "Box2D's own AVX2 path, the native-instruction-set comparison beside rtp's \
                         native build; NDEBUG as in the SSE2 build")
            } else {
                setting("instruction set", "float, SSE2 (the crate's simd-avx2 feature off), -O2, NDEBUG",
                        "Box2D's default x86-64 path; NDEBUG (workers/.cargo/config.toml) as in its \
                         own release build: the crate's cc build defines none, so every internal \
                         assertion would run in the timed step")
            },
        ];
        s.push(setting("subStepCount on springs without contacts", 1,
                       "the spring force is held over the step, so one substep makes it \
                        semi-implicit Euler, as for the other peers"));
        s.push(setting("subStepCount", substeps(variant),
                       if variant == "iterations-10" {
                           "equal iterations (default 4): v3's substep is its iteration"
                       } else {
                           "Box2D v3's documented default, passed to b2World_Step"
                       }));
        s
    }
    fn unsupported(&self, scene: &Scene, _variant: &str) -> Option<String> {
        if !scene.planar {
            return Some("Box2D v3 is a 2D engine: it runs planar scenes only".into());
        }
        scene.particles_unsupported("Box2D v3")
    }
    fn not_applicable(&self, scene: &Scene, variant: &str) -> Option<String> {
        scene.iterations_not_applicable(variant,
                                        "substeps as iterations matter only with contacts here")
    }
    /// substeps: b2World_Step's subStepCount; v3 has no iteration count (one biased solve and
    /// one relax pass a substep)
    fn tune(&self, _variant: &str, knobs: &Knobs) -> Result<Vec<Setting>, String> {
        physbench_worker::tune_substeps_only("Box2D v3", "b2World_Step", knobs)
    }
    fn create(&self, scene: &Scene, variant: &str, knobs: &Knobs)
        -> Result<Box<dyn World>, String> {
        unsafe {
            let mut def = b2DefaultWorldDef();
            def.gravity = v2(scene.gravity[0], scene.gravity[1]);
            def.enableSleep = false;
            def.restitutionThreshold = RESTITUTION_THRESHOLD as f32;
            def.maximumLinearSpeed = MAXIMUM_LINEAR_SPEED;
            let world = b2CreateWorld(&def);
            let mut bodies = Vec::with_capacity(scene.bodies.len());
            for b in &scene.bodies {
                let mut bd = b2DefaultBodyDef();
                let q = b.orientation;
                // a planar scene turns about z only: θ = 2 atan2(qz, qw)
                let angle = 2.0 * q[3].atan2(q[0]);
                bd.position = v2(b.position[0], b.position[1]);
                bd.rotation = b2Rot { c: angle.cos() as f32, s: angle.sin() as f32 };
                bd.enableSleep = false;
                if b.mass > 0.0 {
                    bd.type_ = b2BodyType_b2_dynamicBody;
                    bd.linearVelocity = v2(b.linear_velocity[0], b.linear_velocity[1]);
                    bd.angularVelocity = b.angular_velocity[2] as f32;
                }
                let body = b2CreateBody(world, &bd);
                let mut sd = b2DefaultShapeDef();
                sd.density = 0.0;
                sd.material.friction = b.friction as f32;
                sd.material.restitution = b.restitution as f32;
                if !scene.collisions {
                    sd.filter.maskBits = 0;
                }
                match b.shape {
                    Shape::Box { half_extents: h } => {
                        let polygon = b2MakeBox(h[0] as f32, h[1] as f32);
                        b2CreatePolygonShape(body, &sd, &polygon);
                    }
                    Shape::Sphere { radius } => {
                        let circle = b2Circle { center: v2(0.0, 0.0), radius: radius as f32 };
                        b2CreateCircleShape(body, &sd, &circle);
                    }
                    Shape::Plane => {
                        let segment = b2Segment {
                            point1: b2Vec2 { x: -PLANE_HALF_LENGTH, y: 0.0 },
                            point2: b2Vec2 { x: PLANE_HALF_LENGTH, y: 0.0 },
                        };
                        b2CreateSegmentShape(body, &sd, &segment);
                    }
                }
                if b.mass > 0.0 {
                    let inertia = b.principal_inertia();
                    b2Body_SetMassData(body, b2MassData {
                        mass: b.mass as f32,
                        center: v2(0.0, 0.0),
                        rotationalInertia: inertia[2] as f32,
                    });
                }
                bodies.push(body);
            }
            let substeps = if knobs.substeps > 0 {
                knobs.substeps as i32
            } else if scene.springs_without_contacts() {
                1
            } else {
                substeps(variant)
            };
            Ok(Box::new(Box2dWorld { world, bodies, dt: scene.dt as f32, substeps,
                                     counts_contacts: scene.has_contacts(),
                                     contact_data: std::cell::RefCell::new(Vec::new()) }))
        }
    }
}

struct Box2dWorld {
    world: b2WorldId,
    bodies: Vec<b2BodyId>,
    dt: f32,
    substeps: i32,
    counts_contacts: bool,
    contact_data: std::cell::RefCell<Vec<b2ContactData>>, // reused by contact_points
}

impl Drop for Box2dWorld {
    fn drop(&mut self) {
        unsafe { b2DestroyWorld(self.world) };
    }
}

impl World for Box2dWorld {
    fn step(&mut self) {
        // Box2D v3 clears the applied forces at the end of each step
        unsafe { b2World_Step(self.world, self.dt, self.substeps) };
    }
    /// the touching contacts' manifold points, each contact once: from its dynamic body, or
    /// from the lower-indexed of two dynamic bodies
    fn contact_points(&self) -> Option<usize> {
        if !self.counts_contacts {
            return None;
        }
        let mut points = 0usize;
        let mut data = self.contact_data.borrow_mut();
        unsafe {
            for &body in &self.bodies {
                if b2Body_GetType(body) != b2BodyType_b2_dynamicBody {
                    continue;
                }
                let capacity = b2Body_GetContactCapacity(body);
                data.clear();
                data.reserve(capacity.max(0) as usize);
                let filled = b2Body_GetContactData(body, data.as_mut_ptr(), capacity);
                data.set_len(filled.clamp(0, capacity.max(0)) as usize);
                for c in data.iter() {
                    let a = b2Shape_GetBody(c.shapeIdA);
                    let b = b2Shape_GetBody(c.shapeIdB);
                    let other = if a.index1 == body.index1 { b } else { a };
                    if b2Body_GetType(other) != b2BodyType_b2_dynamicBody || body.index1 < other.index1 {
                        points += c.manifold.pointCount.max(0) as usize;
                    }
                }
            }
        }
        Some(points)
    }
    fn state(&self, body: usize) -> State {
        unsafe {
            let id = self.bodies[body];
            let p = b2Body_GetPosition(id);
            let r = b2Body_GetRotation(id);
            let v = b2Body_GetLinearVelocity(id);
            let w = b2Body_GetAngularVelocity(id);
            let half = 0.5 * (r.s as f64).atan2(r.c as f64);
            State {
                position: [p.x as f64, p.y as f64, 0.0],
                orientation: [half.cos(), 0.0, 0.0, half.sin()],
                linear_velocity: [v.x as f64, v.y as f64, 0.0],
                angular_velocity: [0.0, 0.0, w as f64],
            }
        }
    }
    fn add_force_at_point(&mut self, body: usize, force: [f64; 3], point: [f64; 3]) {
        unsafe {
            b2Body_ApplyForce(self.bodies[body], v2(force[0], force[1]), v2(point[0], point[1]), true)
        };
    }
    fn apply_impulse(&mut self, body: usize, impulse: [f64; 3], point: [f64; 3]) {
        unsafe {
            b2Body_ApplyLinearImpulse(self.bodies[body], v2(impulse[0], impulse[1]),
                                      v2(point[0], point[1]), true)
        };
    }
}

fn main() {
    physbench_worker::main(&Box2dV3);
}

#[cfg(test)]
mod tests {
    use super::*;
    use physbench_worker::checks;

    #[test]
    fn friction_mixes_by_the_scenes_pair_rule() {
        checks::pair_friction(&Box2dV3, "default").unwrap();
    }
    #[test]
    fn restitution_mixes_by_the_scenes_pair_rule() {
        checks::pair_restitution(&Box2dV3, "default").unwrap();
    }
    #[test]
    fn the_scenes_mass_and_inertia_reach_the_engine() {
        checks::mass_and_inertia(&Box2dV3, "default").unwrap();
    }
    #[test]
    fn the_plane_segment_is_the_planes_surface() {
        checks::rests_on_the_plane(&Box2dV3, "default").unwrap();
    }
    #[test]
    fn the_substeps_knob_reaches_b2world_step() {
        for n in [1, 4] {
            checks::substeps_reach_the_step(&Box2dV3, "default", n).unwrap();
        }
    }
    #[test]
    fn an_iterations_knob_is_refused_with_the_reason() {
        let knobs = Knobs { iterations: 8, substeps: 0 };
        assert!(Box2dV3.tune("default", &knobs).unwrap_err().contains("no iteration count"));
    }
}
