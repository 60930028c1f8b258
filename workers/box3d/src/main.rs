//! Box3D (Erin Catto's 3D engine, the C library at commit 781673be, built from source by the
//! boxddd-sys crate) as a harness worker: docs/worker-protocol.md. Its API is Box2D v3's in 3D,
//! and the mapping follows the Box2D v3 worker's wherever the two engines agree.

use boxddd_sys::ffi::*;
use physbench_worker::{
    setting, Engine, Knobs, Scene, Setting, Shape, State, World, RESTITUTION_THRESHOLD,
};
use std::sync::Mutex;

struct Box3d;

// the upstream commit boxddd-sys 0.4.0 vendors (its box3d-upstream.toml); the crate exports no
// constant for it, and b3GetVersion answers 0.1.0 for every commit so far
const UPSTREAM_COMMIT: &str = "781673be801569a94be7942848755fc0baad3653";
// Box3D's own default and its benchmarks' setting: 4 substeps, each one biased solve and one
// relax pass
const DEFAULT_SUBSTEPS: i32 = 4;
// equal iterations: the substep is Box3D's iteration (one solve and one relax pass each)
const EQUAL_SUBSTEPS: i32 = 10;
// the static box that stands for a plane: 2 km square, 20 m deep, its top face the plane's
// surface; no scene reaches its edges, and nothing passes 20 m of it in one step
const PLANE_HALF_WIDTH: f32 = 1000.0;
const PLANE_HALF_DEPTH: f32 = 10.0;
// the scenes' speeds stay below 1e5 m/s (docs/scene-format.md); the default clamp is 400 m/s
const MAXIMUM_LINEAR_SPEED: f32 = 1.0e5;

fn substeps(variant: &str) -> i32 {
    if variant == "iterations-10" { EQUAL_SUBSTEPS } else { DEFAULT_SUBSTEPS }
}

fn v3(a: [f64; 3]) -> b3Vec3 {
    b3Vec3 { x: a[0] as f32, y: a[1] as f32, z: a[2] as f32 }
}

fn d3(a: b3Vec3) -> [f64; 3] {
    [a.x as f64, a.y as f64, a.z as f64]
}

/// the SIMD path Box3D's core.h picks for this target: the crate defines BOX3D_DISABLE_SIMD only
/// under its `disable-simd` feature (not enabled here), and this commit has no AVX2 path
fn simd_path() -> &'static str {
    if cfg!(target_arch = "x86_64") || cfg!(target_arch = "x86") {
        "SSE2 (4 lanes)"
    } else if cfg!(target_arch = "aarch64") {
        "NEON (4 lanes)"
    } else {
        "scalar (4-wide emulation)"
    }
}

// The first Box3D assertion that failed in this process since the last world was built. The
// build defines NDEBUG (workers/.cargo/config.toml), as Box3D's release build does, so its
// assertions are compiled out; should one remain, the default handler would trap (a crash). This one records the condition and lets the step go on, and the world then
// reports it: an exploded state (NaN reaching an assertion) as a breakdown, anything else as an
// error. The handler has no context argument, hence the global.
static ASSERTION: Mutex<Option<String>> = Mutex::new(None);

unsafe extern "C" fn record_assertion(condition: *const std::os::raw::c_char,
                                      file: *const std::os::raw::c_char,
                                      line: std::os::raw::c_int) -> std::os::raw::c_int {
    let text = |p: *const std::os::raw::c_char| {
        if p.is_null() {
            String::from("?")
        } else {
            unsafe { std::ffi::CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let mut slot = ASSERTION.lock().unwrap_or_else(|e| e.into_inner());
    if slot.is_none() {
        *slot = Some(format!("{} ({}:{line})", text(condition), text(file)));
    }
    0 // carry on: the worker reports it
}

fn install_assert_handler() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| unsafe { b3SetAssertFcn(Some(record_assertion)) });
}

fn assertion() -> Option<String> {
    ASSERTION.lock().unwrap_or_else(|e| e.into_inner()).clone()
}

impl Engine for Box3d {
    fn name(&self) -> &'static str {
        "box3d"
    }
    fn version(&self) -> String {
        let v = unsafe { b3GetVersion() };
        let precision = if unsafe { b3IsDoublePrecision() } { "double" } else { "float" };
        format!("commit {} (b3GetVersion {}.{}.{}, boxddd-sys 0.4.0; {precision})",
                &UPSTREAM_COMMIT[..8], v.major, v.minor, v.revision)
    }
    fn variants(&self) -> &'static [&'static str] {
        &["default", "iterations-10"]
    }
    fn settings(&self, variant: &str) -> Vec<Setting> {
        vec![
            setting("enableSleep", "false (world and every body)", "sleeping off in every engine"),
            setting("restitutionThreshold", RESTITUTION_THRESHOLD,
                    "the scene's 0.1 m/s (default 1 m/s)"),
            setting("maximumLinearSpeed", MAXIMUM_LINEAR_SPEED,
                    "default 400 m/s would clamp a fast body silently; the scene format allows 1e5"),
            setting("allowFastRotation", "true on every dynamic body (default false)",
                    "Box3D otherwise clamps a body's turn to 0.25π rad a step (47 rad/s at 60 Hz) \
                     silently; the scene format allows 1e5 rad/s (no built-in scene spins past \
                     12 rad/s, so no built-in row changes)"),
            setting("mass data", "b3Body_SetMassData from the scene: mass, diagonal inertia of \
                     the principal moments, centre at the body origin",
                    "every engine integrates the same body; shapes at density 0"),
            setting("gyroscopic torque", "Box3D's own, always on (implicit, one Newton \
                     iteration a substep)", "a free body's angular momentum is kept, as the \
                     scenes need; Box3D has no switch for it"),
            setting("friction / restitution mixing", "Box3D's default callbacks √(μa μb) and \
                     max(ea, eb)", "already the scene's pair rule: no callback is set"),
            setting("plane", "a static box hull (b3MakeOffsetBoxHull) 2 km square and 20 m \
                     deep, its top face at the body's local y = 0",
                    "Box3D has no plane shape; a height field or mesh would add its 5 mm rest \
                     offset (B3_MESH_REST_OFFSET), a hull has none, so the top face is the plane's \
                     surface exactly"),
            setting("shape skin", "none: boxes are b3MakeBoxHull of the scene's half extents, \
                     spheres b3Sphere of its radius",
                    "Box3D's hulls and spheres carry no radius or margin; contacts are \
                     speculative within 4 × B3_LINEAR_SLOP = 2 cm (default)"),
            setting("contact softness", "contactHertz 30, contactDampingRatio 10, contactSpeed \
                     3 m/s (Box3D's defaults; Box3D lowers the hertz to 1/8 of the substep rate \
                     when that is lower, and doubles it against static bodies)",
                    "soft contacts as Box3D tunes them; the push-out speed of an overlap is \
                     capped at 3 m/s"),
            setting("enableContinuous", "true (Box3D's default), no bullet bodies",
                    "continuous collision is each engine's default in the tunnelling scenes \
                     (Box3D's is dynamic against static)"),
            setting("workerCount", "1 (Box3D's default: serial, no task system)",
                    "every worker steps on one thread"),
            setting("planar scenes", "run free in 3D, no motion locks",
                    "as the other 3D workers (Jolt): the scene keeps itself in its plane"),
            setting("collisions off", "every shape's filter maskBits 0",
                    "no pair is ever made: no collision detection"),
            setting("contact storage", "Box3D's growable arrays",
                    "Box3D has no fixed-size contact buffer to size from the scene or overflow"),
            setting("instruction set", simd_path(), "what the crate's build compiles (no disable-simd \
                     feature; Box3D picks the path from the target, and has no AVX2 path)"),
            setting("assertions", "off: NDEBUG (workers/.cargo/config.toml); any that remain are \
                     recorded, not trapped", "as Box3D's own release build; the crate's cc build \
                     defines no NDEBUG, which would run every internal check in the timed step"),
            setting("solver iterations", "one biased solve and one relax pass a substep, one \
                     restitution pass a step (fixed at compile time)",
                    "Box3D's solver: the substep count is its only knob"),
            setting("springs", "external force at the attachment points, from the state at the \
                     start of each step", "the same method as the other peers' springs"),
            setting("subStepCount on springs without contacts", 1,
                    "the spring force is held over the step, so one substep makes it \
                     semi-implicit Euler, as for the other peers"),
            setting("subStepCount", substeps(variant),
                    if variant == "iterations-10" {
                        "equal iterations (default 4): Box3D's substep is its iteration"
                    } else {
                        "Box3D's default, as its own benchmarks run (4 substeps at 60 Hz), passed \
                         to b3World_Step"
                    }),
        ]
    }
    fn unsupported(&self, scene: &Scene, _variant: &str) -> Option<String> {
        scene.particles_unsupported("Box3D")
    }
    fn not_applicable(&self, scene: &Scene, variant: &str) -> Option<String> {
        scene.iterations_not_applicable(variant,
                                        "substeps as iterations matter only with contacts here")
    }
    /// substeps: b3World_Step's subStepCount; Box3D has no iteration count (one biased solve and
    /// one relax pass a substep)
    fn tune(&self, _variant: &str, knobs: &Knobs) -> Result<Vec<Setting>, String> {
        physbench_worker::tune_substeps_only("Box3D", "b3World_Step", knobs)
    }
    fn create(&self, scene: &Scene, variant: &str, knobs: &Knobs)
        -> Result<Box<dyn World>, String> {
        Ok(Box::new(build(scene, variant, knobs)?))
    }
}

/// the scene's world in Box3D, at the variant with a sweep's knobs
fn build(scene: &Scene, variant: &str, knobs: &Knobs) -> Result<Box3dWorld, String> {
    install_assert_handler();
    *ASSERTION.lock().unwrap_or_else(|e| e.into_inner()) = None;
    unsafe {
        let mut def = b3DefaultWorldDef();
        def.gravity = v3(scene.gravity);
        def.enableSleep = false;
        def.restitutionThreshold = RESTITUTION_THRESHOLD as f32;
        def.maximumLinearSpeed = MAXIMUM_LINEAR_SPEED;
        let world = b3CreateWorld(&def);
        if world.index1 == 0 {
            return Err("b3CreateWorld failed (B3_MAX_WORLDS in use?)".into());
        }
        let mut bodies = Vec::with_capacity(scene.bodies.len());
        for b in &scene.bodies {
            let dynamic = b.mass > 0.0;
            let mut bd = b3DefaultBodyDef();
            let q = b.orientation;
            let norm = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
            bd.position = v3(b.position);
            bd.rotation = b3Quat {
                v: v3([q[1] / norm, q[2] / norm, q[3] / norm]),
                s: (q[0] / norm) as f32,
            };
            bd.enableSleep = false;
            if dynamic {
                bd.type_ = b3BodyType_b3_dynamicBody;
                bd.linearVelocity = v3(b.linear_velocity);
                bd.angularVelocity = v3(b.angular_velocity);
                bd.allowFastRotation = true;
            }
            let body = b3CreateBody(world, &bd);
            let mut sd = b3DefaultShapeDef();
            sd.density = 0.0;
            sd.baseMaterial.friction = b.friction as f32;
            sd.baseMaterial.restitution = b.restitution as f32;
            if !scene.collisions {
                sd.filter.maskBits = 0;
            }
            let shape = match b.shape {
                Shape::Box { half_extents: h } => {
                    let hull = b3MakeBoxHull(h[0] as f32, h[1] as f32, h[2] as f32);
                    b3CreateHullShape(body, &sd, &hull.base)
                }
                Shape::Sphere { radius } => {
                    let sphere = b3Sphere { center: v3([0.0; 3]), radius: radius as f32 };
                    b3CreateSphereShape(body, &sd, &sphere)
                }
                Shape::Plane => {
                    let hull = b3MakeOffsetBoxHull(
                        PLANE_HALF_WIDTH, PLANE_HALF_DEPTH, PLANE_HALF_WIDTH,
                        b3Vec3 { x: 0.0, y: -PLANE_HALF_DEPTH, z: 0.0 });
                    b3CreateHullShape(body, &sd, &hull.base)
                }
            };
            if shape.index1 == 0 {
                b3DestroyWorld(world);
                return Err(format!("Box3D refused the shape of body '{}'", b.name));
            }
            if dynamic {
                b3Body_SetMassData(body, mass_data(b.mass, b.principal_inertia()));
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
        Ok(Box3dWorld { world, bodies, dt: scene.dt as f32, substeps,
                        counts_contacts: scene.has_contacts(), bad_input: None,
                        contact_data: std::cell::RefCell::new(Vec::new()) })
    }
}

fn mass_data(mass: f64, inertia: [f64; 3]) -> b3MassData {
    let zero = b3Vec3 { x: 0.0, y: 0.0, z: 0.0 };
    b3MassData {
        mass: mass as f32,
        center: zero,
        inertia: b3Matrix3 {
            cx: b3Vec3 { x: inertia[0] as f32, ..zero },
            cy: b3Vec3 { y: inertia[1] as f32, ..zero },
            cz: b3Vec3 { z: inertia[2] as f32, ..zero },
        },
    }
}

struct Box3dWorld {
    world: b3WorldId,
    bodies: Vec<b3BodyId>,
    dt: f32,
    substeps: i32,
    counts_contacts: bool,
    bad_input: Option<String>, // a non-finite force or impulse, kept from Box3D's assertions
    contact_data: std::cell::RefCell<Vec<b3ContactData>>, // reused by contact_points
}

impl Drop for Box3dWorld {
    fn drop(&mut self) {
        unsafe { b3DestroyWorld(self.world) };
    }
}

impl Box3dWorld {
    fn all_finite(&self) -> bool {
        (0..self.bodies.len()).all(|i| {
            let s = self.state(i);
            s.position.iter().chain(&s.orientation).chain(&s.linear_velocity)
                .chain(&s.angular_velocity).all(|x| x.is_finite())
        })
    }
}

fn finite(a: [f64; 3]) -> bool {
    a.iter().all(|x| x.is_finite())
}

impl World for Box3dWorld {
    fn step(&mut self) {
        // Box3D clears the applied forces at the end of each step
        unsafe { b3World_Step(self.world, self.dt, self.substeps) };
    }
    fn state(&self, body: usize) -> State {
        unsafe {
            let id = self.bodies[body];
            // the body origin is the centre of mass (mass data centred at it)
            let p = b3Body_GetPosition(id);
            let q = b3Body_GetRotation(id);
            State {
                position: d3(p),
                orientation: [q.s as f64, q.v.x as f64, q.v.y as f64, q.v.z as f64],
                linear_velocity: d3(b3Body_GetLinearVelocity(id)),
                angular_velocity: d3(b3Body_GetAngularVelocity(id)),
            }
        }
    }
    fn add_force_at_point(&mut self, body: usize, force: [f64; 3], point: [f64; 3]) {
        if !(finite(force) && finite(point)) {
            self.bad_input.get_or_insert_with(|| "a non-finite spring force".into());
            return;
        }
        unsafe { b3Body_ApplyForce(self.bodies[body], v3(force), v3(point), true) };
    }
    fn apply_impulse(&mut self, body: usize, impulse: [f64; 3], point: [f64; 3]) {
        unsafe { b3Body_ApplyLinearImpulse(self.bodies[body], v3(impulse), v3(point), true) };
    }
    /// a failed Box3D assertion with the state gone non-finite, or a spring force that did
    fn failure(&self) -> Option<String> {
        if let Some(why) = &self.bad_input {
            return Some(format!("{why} (the state went non-finite)"));
        }
        let assertion = assertion()?;
        (!self.all_finite()).then(|| format!("Box3D assertion failed: {assertion}, with the \
                                              state non-finite"))
    }
    /// a failed Box3D assertion while every body's state is still finite: an internal check of
    /// the engine failed, so its answer is not to be trusted
    fn error(&self) -> Option<String> {
        if self.bad_input.is_some() {
            return None;
        }
        let assertion = assertion()?;
        self.all_finite().then(|| format!("Box3D assertion failed: {assertion}"))
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
                if b3Body_GetType(body) != b3BodyType_b3_dynamicBody {
                    continue;
                }
                let capacity = b3Body_GetContactCapacity(body).max(0);
                data.clear();
                data.reserve(capacity as usize);
                let filled = b3Body_GetContactData(body, data.as_mut_ptr(), capacity);
                data.set_len(filled.clamp(0, capacity) as usize);
                for c in data.iter() {
                    let a = b3Shape_GetBody(c.shapeIdA);
                    let b = b3Shape_GetBody(c.shapeIdB);
                    let other = if a.index1 == body.index1 { b } else { a };
                    if b3Body_GetType(other) == b3BodyType_b3_dynamicBody
                        && other.index1 < body.index1 {
                        continue; // counted from the other body
                    }
                    for m in 0..c.manifoldCount.max(0) as usize {
                        points += (*c.manifolds.add(m)).pointCount.max(0) as usize;
                    }
                }
            }
        }
        Some(points)
    }
}

fn main() {
    physbench_worker::main(&Box3d);
}

#[cfg(test)]
mod tests {
    use super::*;
    use physbench_worker::{checks, load_scene, Body};

    // Box3D keeps its worlds in a global table and the assertion slot is global too: one test
    // at a time
    static SERIAL: Mutex<()> = Mutex::new(());

    fn serial() -> std::sync::MutexGuard<'static, ()> {
        SERIAL.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn cube(half: f64, y: f64) -> Body {
        Body { name: "cube".into(), shape: Shape::Box { half_extents: [half; 3] }, mass: 1.0,
               position: [0.0, y, 0.0], orientation: [1.0, 0.0, 0.0, 0.0],
               linear_velocity: [0.0; 3], angular_velocity: [0.0; 3], friction: 0.5,
               restitution: 0.0 }
    }

    fn ground() -> Body {
        Body { name: "ground".into(), shape: Shape::Plane, mass: 0.0, ..cube(0.5, 0.0) }
    }

    fn scene(bodies: Vec<Body>, collisions: bool) -> Scene {
        let probe_bodies = (0..bodies.len()).filter(|&i| bodies[i].mass > 0.0).collect();
        Scene { name: "test".into(), gravity: [0.0, -9.81, 0.0], dt: 1.0 / 60.0,
                duration: 1.0, planar: false, collisions, bodies, springs: Vec::new(),
                impulses: Vec::new(), has_particles: false, probe_bodies,
                probe_interval: 1.0 / 60.0 }
    }

    #[test]
    fn friction_mixes_by_the_scenes_pair_rule() {
        let _g = serial();
        checks::pair_friction(&Box3d, "default").unwrap();
    }
    #[test]
    fn restitution_mixes_by_the_scenes_pair_rule() {
        let _g = serial();
        checks::pair_restitution(&Box3d, "default").unwrap();
    }
    #[test]
    fn the_scenes_mass_and_inertia_reach_the_engine() {
        let _g = serial();
        checks::mass_and_inertia(&Box3d, "default").unwrap();
    }
    #[test]
    fn the_mass_data_read_back_is_the_scenes() {
        let _g = serial();
        let mut b = cube(0.5, 0.0);
        b.shape = Shape::Box { half_extents: [0.3, 0.2, 0.1] };
        b.mass = 2.0;
        b.orientation = [0.8, 0.6, 0.0, 0.0]; // turned: the local inertia stays the scene's
        let s = scene(vec![b.clone()], true);
        let world = build(&s, "default", &Knobs::default()).unwrap();
        let md = unsafe { b3Body_GetMassData(world.bodies[0]) };
        let i = b.principal_inertia();
        assert!((md.mass as f64 - 2.0).abs() < 1e-6, "mass {}", md.mass);
        assert_eq!(d3(md.center), [0.0; 3]);
        let read = [md.inertia.cx.x as f64, md.inertia.cy.y as f64, md.inertia.cz.z as f64];
        for k in 0..3 {
            assert!((read[k] - i[k]).abs() < 1e-6 * i[k], "inertia {read:?}, scene {i:?}");
        }
        let off = [md.inertia.cx.y, md.inertia.cx.z, md.inertia.cy.x, md.inertia.cy.z,
                   md.inertia.cz.x, md.inertia.cz.y];
        assert!(off.iter().all(|&x| x == 0.0), "off-diagonal inertia {off:?}");
    }
    #[test]
    fn the_plane_box_is_the_planes_surface() {
        let _g = serial();
        checks::rests_on_the_plane(&Box3d, "default").unwrap();
    }
    #[test]
    fn a_box_resting_on_the_plane_stays_put_for_two_steps() {
        let _g = serial();
        // a 10 cm cube touching the plane: the plane box's top face at y = 0 holds it; a surface
        // off by a few mm would drop it, or push it up, by more than the tolerance
        for half in [0.05, 0.5] {
            let s = scene(vec![ground(), cube(half, half)], true);
            let mut world = Box3d.create(&s, "default", &Knobs::default()).unwrap();
            for _ in 0..2 {
                world.step();
            }
            let y = world.state(1).position[1];
            assert!((y - half).abs() < 2e-4, "half extent {half}: the cube moved to y = {y}");
            assert!(world.error().is_none() && world.failure().is_none());
        }
    }
    #[test]
    fn a_turned_plane_turns_its_surface() {
        let _g = serial();
        // the plane turned a quarter turn about z faces -x: its surface is the world's x = 0,
        // solid on +x; a cube touching it from the -x side, in zero gravity, stays where it is
        let half = std::f64::consts::FRAC_PI_4;
        let mut plane = ground();
        plane.orientation = [half.cos(), 0.0, 0.0, half.sin()];
        let mut c = cube(0.5, 0.0);
        c.position = [-0.5, 0.0, 0.0];
        c.linear_velocity = [0.5, 0.0, 0.0]; // pressing into the surface
        let mut s = scene(vec![plane, c], true);
        s.gravity = [0.0; 3];
        let mut world = Box3d.create(&s, "default", &Knobs::default()).unwrap();
        for _ in 0..30 {
            world.step();
        }
        let x = world.state(1).position[0];
        assert!(x < -0.49 && x > -0.52, "the cube's centre is at x = {x}");
    }
    #[test]
    fn the_substeps_knob_reaches_b3world_step() {
        let _g = serial();
        for n in [1, 4] {
            checks::substeps_reach_the_step(&Box3d, "default", n).unwrap();
        }
    }
    #[test]
    fn the_variants_step_with_their_substeps() {
        let _g = serial();
        // one free-fall step of 0.1 s: n substeps drop a body g dt² (n + 1) / 2n
        for (variant, n) in [("default", 4.0), ("iterations-10", 10.0)] {
            let mut b = cube(0.5, 10.0);
            b.mass = 1.0;
            let mut s = scene(vec![b, ground()], true);
            s.dt = 0.1;
            let mut world = Box3d.create(&s, variant, &Knobs::default()).unwrap();
            world.step();
            let drop = 10.0 - world.state(0).position[1];
            let expected = 9.81 * 0.01 * (n + 1.0) / (2.0 * n);
            assert!((drop - expected).abs() < 1e-3 * expected, "{variant}: dropped {drop}");
        }
    }
    #[test]
    fn an_iterations_knob_is_refused_with_the_reason() {
        let knobs = Knobs { iterations: 8, substeps: 0 };
        assert!(Box3d.tune("default", &knobs).unwrap_err().contains("no iteration count"));
        let knobs = Knobs { iterations: 0, substeps: 6 };
        assert_eq!(Box3d.tune("default", &knobs).unwrap()[0].value, "6");
    }
    #[test]
    fn collisions_off_lets_a_box_fall_through_the_plane() {
        let _g = serial();
        let s = scene(vec![ground(), cube(0.5, 0.5)], false);
        let mut world = Box3d.create(&s, "default", &Knobs::default()).unwrap();
        for _ in 0..60 {
            world.step();
        }
        // one second of free fall from 0.5 m
        let y = world.state(1).position[1];
        assert!(y < -4.0, "the cube is at y = {y}: something still collided");
        assert_eq!(world.contact_points(), None);
    }
    #[test]
    fn contact_points_count_a_resting_box_once() {
        let _g = serial();
        // a cube on the plane and a second cube on it: two face contacts of 4 points each
        let mut top = cube(0.5, 1.5);
        top.name = "top".into();
        let s = scene(vec![ground(), cube(0.5, 0.5), top], true);
        let mut world = Box3d.create(&s, "default", &Knobs::default()).unwrap();
        for _ in 0..10 {
            world.step();
        }
        assert_eq!(world.contact_points(), Some(8));
    }
    #[test]
    fn a_fast_spin_is_not_clamped() {
        let _g = serial();
        // 100 rad/s about y in free flight: past Box3D's default 0.25π rad a step (47 rad/s)
        let mut b = cube(0.5, 0.0);
        b.angular_velocity = [0.0, 100.0, 0.0];
        let mut s = scene(vec![b], true);
        s.gravity = [0.0; 3];
        let mut world = Box3d.create(&s, "default", &Knobs::default()).unwrap();
        world.step();
        let w = world.state(0).angular_velocity[1];
        assert!((w - 100.0).abs() < 1e-3, "ω = {w} rad/s after a step");
    }
    #[test]
    fn the_version_names_the_commit_and_the_librarys_own_version() {
        let v = Box3d.version();
        assert!(v.starts_with("commit 781673be"), "{v}");
        assert!(v.contains("b3GetVersion 0.1.0") && v.contains("float"), "{v}");
    }
    #[test]
    fn particles_are_unsupported_with_a_reason() {
        let mut s = scene(vec![cube(0.5, 0.0)], true);
        s.has_particles = true;
        assert!(Box3d.unsupported(&s, "default").unwrap().contains("Box3D"));
    }
    #[test]
    fn a_scene_file_runs_through_the_worker_mapping() {
        let _g = serial();
        // the scene format's own defaults, read back as the harness writes them
        let path = std::env::temp_dir().join(format!("physbench-box3d-{}.json",
                                                     std::process::id()));
        std::fs::write(&path, r#"{"name": "s", "dt": 0.01, "duration": 0.1,
            "bodies": [{"name": "g", "shape": {"type": "plane"}},
                       {"name": "b", "shape": {"type": "sphere", "radius": 0.5},
                        "mass": 2, "position": [0, 0.5, 0]}]}"#).unwrap();
        let s = load_scene(path.to_str().unwrap()).unwrap();
        let mut world = Box3d.create(&s, "default", &Knobs::default()).unwrap();
        for _ in 0..s.step_count() {
            world.step();
        }
        let y = world.state(1).position[1];
        assert!((y - 0.5).abs() < 2e-3, "a resting sphere moved to y = {y}");
    }
}
