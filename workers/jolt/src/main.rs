//! Jolt Physics (5.6.0, single precision, through the joltc C wrapper of the oxijolt-sys crate)
//! as a harness worker: docs/worker-protocol.md.

use oxijolt_sys::*;
use physbench_worker::{
    setting, Engine, Knobs, Scene, Setting, Shape, State, World, RESTITUTION_THRESHOLD,
};
use std::ptr;

struct Jolt;

// the Jolt release that oxijolt-sys 1.5.0 vendors (its own version says so: 1.5.0+jolt-5.6.0);
// joltc exports no version function, so the version names the commits the crate's build used
const JOLT_VERSION: &str = "5.6.0";
// Jolt's default rounding of a box's edges (cDefaultConvexRadius), kept where the box allows it
const DEFAULT_CONVEX_RADIUS: f32 = 0.05;
// a plane shape's extent for the broad phase (Jolt's default): no scene reaches it
const PLANE_HALF_EXTENT: f32 = 1000.0;
// the scene format's speed limits (docs/scene-format.md); Jolt's defaults clamp at 500 m/s and
// 0.25 π × 60 ≈ 47 rad/s
const MAXIMUM_LINEAR_SPEED: f32 = 1.0e5;
const MAXIMUM_ANGULAR_SPEED: f32 = 1.0e5;
// Jolt's defaults for the world's buffers, raised with the body count (see `capacities`)
const DEFAULT_MAX_BODY_PAIRS: u32 = 65536;
const DEFAULT_MAX_CONTACT_CONSTRAINTS: u32 = 10240;
// bytes of Jolt's per-step scratch memory; it falls back to malloc beyond this
const TEMP_ALLOCATOR_BYTES: u32 = 16 << 20;

// object and broad-phase layers: one for static bodies, one for moving ones
const LAYER_STATIC: JPH_ObjectLayer = 0;
const LAYER_MOVING: JPH_ObjectLayer = 1;

/// the world's buffers: a pair or a contact past them is dropped, and Jolt says so after the step
/// (a run that hits one is an `error`); Jolt's defaults hold scenes up to about 2,500 boxes
fn capacities(scene: &Scene) -> (u32, u32, u32) {
    let n = scene.bodies.len() as u32;
    let max_bodies = n.max(16);
    // each box in a pyramid or pile touches about six others and keeps a constraint per pair
    let pairs = DEFAULT_MAX_BODY_PAIRS.max(16 * n);
    let contacts = DEFAULT_MAX_CONTACT_CONSTRAINTS.max(8 * n);
    (max_bodies, pairs, contacts)
}

/// Jolt asks for a convex radius no larger than the box's smallest half extent; a box thinner
/// than 20 cm gets half its smallest half extent instead of the default 5 cm
fn convex_radius(half_extents: [f64; 3]) -> f32 {
    let smallest = half_extents.iter().cloned().fold(f64::INFINITY, f64::min) as f32;
    DEFAULT_CONVEX_RADIUS.min(0.5 * smallest)
}

fn vec3(a: [f64; 3]) -> JPH_Vec3 {
    JPH_Vec3 { x: a[0] as f32, y: a[1] as f32, z: a[2] as f32 }
}

fn init_jolt() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| unsafe {
        assert!(JPH_Init(), "JPH_Init failed");
        // one set of callbacks for every listener (joltc keeps them globally); each listener's
        // user data is its world's counter
        static PROCS: JPH_ContactListener_Procs = JPH_ContactListener_Procs {
            OnContactValidate: None,
            OnContactAdded: Some(count_manifold_points),
            OnContactPersisted: Some(count_manifold_points),
            OnContactRemoved: None,
        };
        JPH_ContactListener_SetProcs(&PROCS);
    });
}

/// Jolt's contact points: its C API has no walk over the step's contacts, so a contact listener
/// counts them. Jolt calls it once for each manifold it turns into a contact constraint in a step
/// (new or kept, cached pairs included), with the manifold's points, which are the constraint's
/// (a body with continuous motion may repeat a call; every body here moves discretely). The
/// callbacks run inside Jolt's step, so the count's cost is in its timing, unlike the other
/// workers' counts (docs/metrics.md)
unsafe extern "C" fn count_manifold_points(user: *mut std::os::raw::c_void, _body1: *const JPH_Body,
                                           _body2: *const JPH_Body,
                                           manifold: *const JPH_ContactManifold,
                                           _settings: *mut JPH_ContactSettings) {
    // the single-threaded job system calls it on the stepping thread; atomic all the same
    let points = unsafe { &*(user as *const std::sync::atomic::AtomicUsize) };
    let count = unsafe { JPH_ContactManifold_GetPointCount(manifold) } as usize;
    points.fetch_add(count, std::sync::atomic::Ordering::Relaxed);
}

impl Engine for Jolt {
    fn name(&self) -> &'static str {
        "jolt"
    }
    fn version(&self) -> String {
        format!("{JOLT_VERSION} (float; Jolt {}, joltc {})", &JOLT_COMMIT[..10], &JOLTC_COMMIT[..10])
    }
    fn variants(&self) -> &'static [&'static str] {
        &["default", "iterations-10"]
    }
    fn settings(&self, _variant: &str) -> Vec<Setting> {
        vec![
            setting("instruction set",
                    "AVX2, FMA, LZCNT, TZCNT, F16C, SSE4.2 (Jolt's CMake defaults, as oxijolt-sys \
                     builds it; no AVX-512), float",
                    "Jolt's own default build; beside rtp's native build, not its -x86-64 one"),
            setting("allowSleeping", "false (world and every body)", "sleeping off in every engine"),
            setting("numVelocitySteps / numPositionSteps", "10 / 2 (Jolt's defaults)",
                    "Jolt's default already is 10 velocity iterations, the equal-iterations \
                     setting: its iterations-10 variant makes no row"),
            setting("minVelocityForRestitution", RESTITUTION_THRESHOLD,
                    "the scene's 0.1 m/s (default 1 m/s)"),
            setting("penetrationSlop", "0.02 m (Jolt's default)",
                    "penetration Jolt leaves uncorrected in its position steps"),
            setting("speculativeContactDistance", "0.02 m (Jolt's default)",
                    "contacts form when shapes come within 2 cm"),
            setting("baumgarte", "0.2 (Jolt's default)", "position correction per position step"),
            setting("box convex radius", "min(0.05 m, half the smallest half extent)",
                    "Jolt's default 0.05 m where the box allows it (Jolt asks for a radius no \
                     larger than the smallest half extent: the 5 cm tunnelling wall gets 1.25 cm, \
                     its 10 cm box 2.5 cm); the faces stay the scene's, edges and corners are \
                     rounded by it"),
            setting("plane", "a static PlaneShape, the body's local y = 0 surface, half extent \
                     1 km", "Jolt's own plane: solid below, its surface is the scene's plane \
                     (a large box would add edges and a finite depth)"),
            setting("collisionSteps", "1 per step", "the scene's dt is the step, as for every \
                     peer (Jolt advises one collision step per 1/60 s)"),
            setting("linear / angular damping", "0 (default 0.05 each)",
                    "the scenes have no damping"),
            setting("maxLinearVelocity / maxAngularVelocity", "1e5 m/s, 1e5 rad/s \
                     (default 500 m/s, 47 rad/s)", "the scene format's limits: no silent clamp"),
            setting("applyGyroscopicForce", "true (default false)",
                    "a free body's angular momentum, not its angular velocity, is constant: \
                     without it the tumbling box cannot flip"),
            setting("mass properties", "MassAndInertiaProvided, from the scene",
                    "every engine integrates the same body"),
            setting("friction / restitution combining", "Jolt's own √(μa μb) and max(ea, eb)",
                    "already the scene's pair rule"),
            setting("motion quality", "Discrete (Jolt's default)",
                    "continuous collision is each engine's default in the tunnelling scenes"),
            setting("job system", "JobSystemSingleThreaded (one thread)",
                    "every worker steps on one thread"),
            setting("maxBodyPairs / maxContactConstraints", "max(65536, 16 n) / max(10240, 8 n) \
                     for n bodies", "Jolt's defaults, raised for large scenes; a full buffer \
                     drops contacts and the run is an error"),
            setting("springs", "external force at the attachment points, from the state at the \
                     start of each step", "the same method as the other peers' springs"),
            setting("contact listener", "on scenes with collisions: counts each step's contact \
                     points (OnContactAdded / OnContactPersisted)", "the only way the C API gives \
                     them; its callbacks run inside the timed step, once a manifold"),
        ]
    }
    fn unsupported(&self, scene: &Scene, _variant: &str) -> Option<String> {
        scene.particles_unsupported("Jolt")
    }
    fn not_applicable(&self, _scene: &Scene, variant: &str) -> Option<String> {
        (variant == "iterations-10").then(|| {
            "Jolt's default already is 10 velocity steps (with 2 position steps): equal \
             iterations is its default row".into()
        })
    }
    /// substeps: PhysicsSystem::Update's collision steps (each a whole step of dt/N: Jolt's own
    /// substeps); iterations: PhysicsSettings::mNumVelocitySteps (default 10)
    fn tune(&self, _variant: &str, knobs: &Knobs) -> Result<Vec<Setting>, String> {
        let mut s = Vec::new();
        if knobs.substeps > 0 {
            s.push(setting("collision steps", knobs.substeps,
                           "the sweep's substeps (--sweep-substeps): PhysicsSystem::Update's \
                            inCollisionSteps, each a whole step of dt/N"));
        }
        if knobs.iterations > 0 {
            s.push(setting("numVelocitySteps", knobs.iterations,
                           "the sweep's iterations (--sweep-iterations): \
                            PhysicsSettings::mNumVelocitySteps (default 10)"));
        }
        Ok(s)
    }
    fn create(&self, scene: &Scene, _variant: &str, knobs: &Knobs)
        -> Result<Box<dyn World>, String> {
        init_jolt();
        unsafe {
            let layers = JPH_BroadPhaseLayerInterfaceTable_Create(2, 2);
            JPH_BroadPhaseLayerInterfaceTable_MapObjectToBroadPhaseLayer(layers, LAYER_STATIC, 0);
            JPH_BroadPhaseLayerInterfaceTable_MapObjectToBroadPhaseLayer(layers, LAYER_MOVING, 1);
            let pairs = JPH_ObjectLayerPairFilterTable_Create(2);
            // a scene without collisions runs no collision detection: no pair ever forms
            if scene.collisions {
                JPH_ObjectLayerPairFilterTable_EnableCollision(pairs, LAYER_MOVING, LAYER_MOVING);
                JPH_ObjectLayerPairFilterTable_EnableCollision(pairs, LAYER_MOVING, LAYER_STATIC);
            }
            let against_broad_phase = JPH_ObjectVsBroadPhaseLayerFilterTable_Create(layers, 2,
                                                                                    pairs, 2);
            let (max_bodies, max_pairs, max_contacts) = capacities(scene);
            let system_settings = JPH_PhysicsSystemSettings {
                maxBodies: max_bodies,
                numBodyMutexes: 0,
                maxBodyPairs: max_pairs,
                maxContactConstraints: max_contacts,
                _padding: 0,
                broadPhaseLayerInterface: layers,
                objectLayerPairFilter: pairs,
                objectVsBroadPhaseLayerFilter: against_broad_phase,
            };
            // the system owns the layer interface and both filters from here on
            let system = JPH_PhysicsSystem_Create(&system_settings);
            if system.is_null() {
                return Err("JPH_PhysicsSystem_Create failed".into());
            }
            let mut physics: JPH_PhysicsSettings = std::mem::zeroed();
            JPH_PhysicsSystem_GetPhysicsSettings(system, &mut physics);
            physics.allowSleeping = false;
            physics.minVelocityForRestitution = RESTITUTION_THRESHOLD as f32;
            if knobs.iterations > 0 {
                physics.numVelocitySteps = knobs.iterations as _;
            }
            JPH_PhysicsSystem_SetPhysicsSettings(system, &mut physics);
            JPH_PhysicsSystem_SetGravity(system, &vec3(scene.gravity));

            let interface = JPH_PhysicsSystem_GetBodyInterfaceNoLock(system);
            let mut bodies = Vec::with_capacity(scene.bodies.len());
            for b in &scene.bodies {
                let shape: *mut JPH_Shape = match b.shape {
                    Shape::Box { half_extents: h } => {
                        JPH_BoxShape_Create(&vec3(h), convex_radius(h)) as *mut JPH_Shape
                    }
                    Shape::Sphere { radius } => JPH_SphereShape_Create(radius as f32) as *mut _,
                    Shape::Plane => {
                        let plane = JPH_Plane { normal: JPH_Vec3 { x: 0.0, y: 1.0, z: 0.0 },
                                                distance: 0.0 };
                        JPH_PlaneShape_Create(&plane, ptr::null(), PLANE_HALF_EXTENT) as *mut _
                    }
                };
                if shape.is_null() {
                    return Err(format!("Jolt refused the shape of body '{}'", b.name));
                }
                let q = b.orientation;
                let norm = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
                let rotation = JPH_Quat { x: (q[1] / norm) as f32, y: (q[2] / norm) as f32,
                                          z: (q[3] / norm) as f32, w: (q[0] / norm) as f32 };
                let dynamic = b.mass > 0.0;
                let settings = JPH_BodyCreationSettings_Create3(
                    shape, &vec3(b.position), &rotation,
                    if dynamic { JPH_MotionType_Dynamic } else { JPH_MotionType_Static },
                    if dynamic { LAYER_MOVING } else { LAYER_STATIC });
                // the body holds its own reference to the shape
                JPH_Shape_Destroy(shape);
                JPH_BodyCreationSettings_SetAllowSleeping(settings, false);
                JPH_BodyCreationSettings_SetFriction(settings, b.friction as f32);
                JPH_BodyCreationSettings_SetRestitution(settings, b.restitution as f32);
                if dynamic {
                    JPH_BodyCreationSettings_SetLinearVelocity(settings, &vec3(b.linear_velocity));
                    JPH_BodyCreationSettings_SetAngularVelocity(settings,
                                                                &vec3(b.angular_velocity));
                    JPH_BodyCreationSettings_SetLinearDamping(settings, 0.0);
                    JPH_BodyCreationSettings_SetAngularDamping(settings, 0.0);
                    JPH_BodyCreationSettings_SetMaxLinearVelocity(settings, MAXIMUM_LINEAR_SPEED);
                    JPH_BodyCreationSettings_SetMaxAngularVelocity(settings,
                                                                   MAXIMUM_ANGULAR_SPEED);
                    JPH_BodyCreationSettings_SetApplyGyroscopicForce(settings, true);
                    let i = b.principal_inertia();
                    let zero = JPH_Vec4 { x: 0.0, y: 0.0, z: 0.0, w: 0.0 };
                    let mut inertia = JPH_Mat4 { column: [zero; 4] };
                    inertia.column[0].x = i[0] as f32;
                    inertia.column[1].y = i[1] as f32;
                    inertia.column[2].z = i[2] as f32;
                    inertia.column[3].w = 1.0;
                    JPH_BodyCreationSettings_SetOverrideMassProperties(
                        settings, JPH_OverrideMassProperties_MassAndInertiaProvided);
                    JPH_BodyCreationSettings_SetMassPropertiesOverride(
                        settings, &JPH_MassProperties { mass: b.mass as f32, inertia });
                }
                let activation = if dynamic { JPH_Activation_Activate }
                                 else { JPH_Activation_DontActivate };
                let id = JPH_BodyInterface_CreateAndAddBody(interface, settings, activation);
                JPH_BodyCreationSettings_Destroy(settings);
                bodies.push(id);
            }
            JPH_PhysicsSystem_OptimizeBroadPhase(system);
            // a scene with collisions counts its contact points (no listener otherwise: nothing
            // to count, and no callback cost)
            let points = Box::new(std::sync::atomic::AtomicUsize::new(0));
            let listener = if scene.collisions {
                let listener = JPH_ContactListener_Create(
                    &*points as *const std::sync::atomic::AtomicUsize as *mut std::os::raw::c_void);
                if listener.is_null() {
                    return Err("JPH_ContactListener_Create failed".into());
                }
                JPH_PhysicsSystem_SetContactListener(system, listener);
                listener
            } else {
                ptr::null_mut()
            };
            Ok(Box::new(JoltWorld {
                system,
                interface,
                jobs: JPH_JobSystemSingleThreaded_Create(0),
                scratch: JPH_TempAllocator_Create(TEMP_ALLOCATOR_BYTES),
                bodies,
                dt: scene.dt as f32,
                collision_steps: knobs.substeps.max(1) as i32,
                overflow: None,
                listener,
                points,
            }))
        }
    }
}

struct JoltWorld {
    system: *mut JPH_PhysicsSystem,
    interface: *mut JPH_BodyInterface,
    jobs: *mut JPH_JobSystem,
    scratch: *mut JPH_TempAllocator,
    bodies: Vec<JPH_BodyID>,
    dt: f32,
    collision_steps: i32, // PhysicsSystem::Update's inCollisionSteps: 1, or a sweep's substeps
    overflow: Option<String>,
    listener: *mut JPH_ContactListener, // null on a scene without collisions
    points: Box<std::sync::atomic::AtomicUsize>, // the listener's count since the last read
}

impl Drop for JoltWorld {
    fn drop(&mut self) {
        unsafe {
            for &id in &self.bodies {
                JPH_BodyInterface_RemoveAndDestroyBody(self.interface, id);
            }
            JPH_PhysicsSystem_Destroy(self.system);
            if !self.listener.is_null() {
                JPH_ContactListener_Destroy(self.listener);
            }
            JPH_JobSystem_Destroy(self.jobs);
            JPH_TempAllocator_Destroy(self.scratch);
        }
    }
}

impl World for JoltWorld {
    fn step(&mut self) {
        // Jolt clears the forces added for a step at its end
        let result = unsafe { JPH_PhysicsSystem_Update2(self.system, self.dt, self.collision_steps,
                                                        self.scratch,
                                                        self.jobs) };
        if result != JPH_PhysicsUpdateError_None && self.overflow.is_none() {
            let mut full = Vec::new();
            if result & JPH_PhysicsUpdateError_ManifoldCacheFull != 0 {
                full.push("manifold cache");
            }
            if result & JPH_PhysicsUpdateError_BodyPairCacheFull != 0 {
                full.push("body pair cache");
            }
            if result & JPH_PhysicsUpdateError_ContactConstraintsFull != 0 {
                full.push("contact constraint buffer");
            }
            self.overflow = Some(format!("Jolt's {} overflowed and dropped contacts",
                                         full.join(" and ")));
        }
    }
    fn state(&self, body: usize) -> State {
        unsafe {
            let id = self.bodies[body];
            let zero = JPH_Vec3 { x: 0.0, y: 0.0, z: 0.0 };
            let (mut p, mut v, mut w) = (zero, zero, zero);
            let mut q = JPH_Quat { x: 0.0, y: 0.0, z: 0.0, w: 1.0 };
            JPH_BodyInterface_GetCenterOfMassPosition(self.interface, id, &mut p);
            JPH_BodyInterface_GetRotation(self.interface, id, &mut q);
            JPH_BodyInterface_GetLinearVelocity(self.interface, id, &mut v);
            JPH_BodyInterface_GetAngularVelocity(self.interface, id, &mut w);
            let d = |a: JPH_Vec3| [a.x as f64, a.y as f64, a.z as f64];
            State {
                position: d(p),
                orientation: [q.w as f64, q.x as f64, q.y as f64, q.z as f64],
                linear_velocity: d(v),
                angular_velocity: d(w),
            }
        }
    }
    fn add_force_at_point(&mut self, body: usize, force: [f64; 3], point: [f64; 3]) {
        unsafe {
            JPH_BodyInterface_AddForce2(self.interface, self.bodies[body], &mut vec3(force),
                                        &mut vec3(point))
        };
    }
    fn apply_impulse(&mut self, body: usize, impulse: [f64; 3], point: [f64; 3]) {
        unsafe {
            JPH_BodyInterface_AddImpulse2(self.interface, self.bodies[body], &mut vec3(impulse),
                                          &mut vec3(point))
        };
    }
    fn error(&self) -> Option<String> {
        self.overflow.clone()
    }
    /// the points of every manifold Jolt made a contact constraint of in the last step, as its
    /// contact listener counted them during the step
    fn contact_points(&self) -> Option<usize> {
        if self.listener.is_null() {
            return None;
        }
        Some(self.points.swap(0, std::sync::atomic::Ordering::Relaxed))
    }
}

fn main() {
    physbench_worker::main(&Jolt);
}

#[cfg(test)]
mod tests {
    use super::*;
    use physbench_worker::checks;

    #[test]
    fn friction_mixes_by_the_scenes_pair_rule() {
        checks::pair_friction(&Jolt, "default").unwrap();
    }
    #[test]
    fn restitution_mixes_by_the_scenes_pair_rule() {
        checks::pair_restitution(&Jolt, "default").unwrap();
    }
    #[test]
    fn the_scenes_mass_and_inertia_reach_the_engine() {
        checks::mass_and_inertia(&Jolt, "default").unwrap();
    }
    #[test]
    fn the_plane_is_the_bodys_y_zero_surface() {
        checks::rests_on_the_plane(&Jolt, "default").unwrap();
    }
    #[test]
    fn the_substeps_knob_reaches_the_collision_steps() {
        for n in [1, 4] {
            checks::substeps_reach_the_step(&Jolt, "default", n).unwrap();
        }
    }
    #[test]
    fn a_thin_box_gets_a_convex_radius_it_can_hold() {
        assert_eq!(convex_radius([0.5, 0.5, 0.5]), DEFAULT_CONVEX_RADIUS);
        // a 4 cm plate: half of its 2 cm half thickness
        assert!((convex_radius([0.5, 0.02, 0.5]) - 0.01).abs() < 1e-7);
    }
    #[test]
    fn the_buffers_grow_with_the_body_count() {
        let mut scene = physbench_worker::load_scene(&write_scene(6000)).unwrap();
        let (bodies, pairs, contacts) = capacities(&scene);
        assert_eq!(bodies, 6000);
        assert!(pairs >= 16 * 6000 && contacts >= 8 * 6000);
        scene.bodies.truncate(10);
        let (_, pairs, contacts) = capacities(&scene);
        assert_eq!((pairs, contacts), (DEFAULT_MAX_BODY_PAIRS, DEFAULT_MAX_CONTACT_CONSTRAINTS));
    }

    fn write_scene(boxes: usize) -> String {
        let body = r#"{"name": "b", "shape": {"type": "box", "half_extents": [0.5, 0.5, 0.5]},
                       "mass": 1}"#;
        let text = format!(r#"{{"name": "many", "dt": 0.01, "duration": 0.01, "bodies": [{}]}}"#,
                           vec![body; boxes].join(","));
        let path = std::env::temp_dir().join(format!("physbench-jolt-{}.json", std::process::id()));
        std::fs::write(&path, text).unwrap();
        path.to_string_lossy().into_owned()
    }
}
