//! NVIDIA PhysX 5.1.3 (single precision, CPU only, through the generated C wrapper of the
//! physx-sys crate) as a harness worker: docs/worker-protocol.md.
//!
//! Over 800 lines: 300 of them are the crate's own tests of its mapping (the plane's side, the
//! pair rule, the substeps, the held forces, sleeping), which live beside what they test.

use physbench_worker::{
    setting, Body, Engine, Knobs, Scene, Setting, Shape, State, World, RESTITUTION_THRESHOLD,
};
use physx_sys::*;
use std::collections::HashMap;
use std::ffi::{c_void, CStr};
use std::ptr::{null, null_mut};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, OnceLock};

struct PhysX;

// the release physx-sys 0.11.5 vendors; PxCreateFoundation and PxCreatePhysics refuse any other
// version number ("Wrong version"), so a worker that starts runs exactly this release
const PHYSX_VERSION: u32 = physx_sys::version(5, 1, 3);
const CRATE: &str = "physx-sys 0.11.5";

// PhysX's defaults for a rigid dynamic (PxRigidDynamic::setSolverIterationCounts)
const DEFAULT_POSITION_ITERATIONS: u32 = 4;
const DEFAULT_VELOCITY_ITERATIONS: u32 = 1;
// equal iterations: PhysX's position iterations are its biased solve passes, the nearest it has
// to the other engines' 10 velocity iterations
const EQUAL_POSITION_ITERATIONS: u32 = 10;
// the scene format's speed limit (docs/scene-format.md); PhysX clamps a dynamic body's angular
// speed at 100 rad/s by default. Its linear clamp is already far above (1e16 m/s): left alone
const MAXIMUM_ANGULAR_SPEED: f32 = 1.0e5;
// PhysX's default tolerances scale (PxTolerancesScale()): 1 m, 10 m/s
const SCALE_LENGTH: f32 = 1.0;
const SCALE_SPEED: f32 = 10.0;

fn solver(variant: &str) -> PxSolverType {
    if variant == "tgs" { PxSolverType::Tgs } else { PxSolverType::Pgs }
}

/// position iterations on every dynamic body: a sweep's knob, else the variant's
fn position_iterations(variant: &str, knobs: &Knobs) -> u32 {
    if knobs.iterations > 0 {
        knobs.iterations as u32
    } else if variant == "iterations-10" {
        EQUAL_POSITION_ITERATIONS
    } else {
        DEFAULT_POSITION_ITERATIONS
    }
}

/// a material's friction coefficient: PhysX has no √(μa μb) combine mode, but with eMULTIPLY
/// the product of the two materials' roots is exactly the scene's pair rule, for every pair
fn material_friction(friction: f64) -> f32 {
    friction.sqrt() as f32
}

fn vec3(a: [f64; 3]) -> PxVec3 {
    PxVec3 { x: a[0] as f32, y: a[1] as f32, z: a[2] as f32 }
}

fn transform(position: [f64; 3], orientation: [f64; 4]) -> PxTransform {
    let q = orientation;
    let norm = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    PxTransform {
        q: PxQuat { x: (q[1] / norm) as f32, y: (q[2] / norm) as f32, z: (q[3] / norm) as f32,
                    w: (q[0] / norm) as f32 },
        p: vec3(position),
    }
}

/// the plane shape's pose in its body: PxPlaneGeometry is the half space x ≤ 0 of its shape
/// frame (normal +x); a quarter turn about z carries +x to +y, so the surface is the body's
/// local y = 0 and the solid side is below it
fn plane_local_pose() -> PxTransform {
    let half = std::f32::consts::FRAC_PI_4;
    PxTransform { q: PxQuat { x: 0.0, y: 0.0, z: half.sin(), w: half.cos() },
                  p: PxVec3 { x: 0.0, y: 0.0, z: 0.0 } }
}

/// the process's one foundation and physics object (PhysX allows one foundation a process)
struct Sdk {
    #[allow(dead_code)] // lives as long as the process; the tests reach it
    foundation: *mut PxFoundation,
    physics: *mut PxPhysics,
}
unsafe impl Send for Sdk {}
unsafe impl Sync for Sdk {}

static SDK: OnceLock<Result<Sdk, String>> = OnceLock::new();
// every error PhysX reported through the foundation's error callback, in order
static ERRORS: Mutex<Vec<String>> = Mutex::new(Vec::new());

fn errors() -> std::sync::MutexGuard<'static, Vec<String>> {
    ERRORS.lock().unwrap_or_else(|e| e.into_inner())
}

/// PhysX's error callback: debug information and performance advice are printed only; anything
/// else (an invalid parameter or operation, an internal error, an allocation that failed, a
/// warning that it dropped something) is kept, and a world that sees one ends its run as an error
unsafe extern "C" fn record_error(code: PxErrorCode, message: *const i8, file: *const i8,
                                  line: u32, _user: *const c_void) {
    let text = |p: *const i8| if p.is_null() {
        String::new()
    } else {
        unsafe { CStr::from_ptr(p) }.to_string_lossy().trim_end().to_string()
    };
    let report = format!("PhysX {code:?}: {} ({}:{line})", text(message), text(file));
    eprintln!("{report}");
    if !matches!(code, PxErrorCode::DebugInfo | PxErrorCode::PerfWarning) {
        errors().push(report);
    }
}

fn sdk() -> Result<&'static Sdk, String> {
    SDK.get_or_init(|| unsafe {
        let callback = create_error_callback(record_error, null_mut());
        let foundation = phys_PxCreateFoundation(PHYSX_VERSION, get_default_allocator().cast(),
                                                 callback);
        if foundation.is_null() {
            return Err(format!("PxCreateFoundation refused version {PHYSX_VERSION:#x}: {}",
                               errors().join("; ")));
        }
        let scale = PxTolerancesScale { length: SCALE_LENGTH, speed: SCALE_SPEED };
        // no allocation tracking, no visual debugger: PxCreatePhysics's own defaults
        let physics = phys_PxCreatePhysics(PHYSX_VERSION, foundation, &scale, false, null_mut(),
                                           null_mut());
        if physics.is_null() {
            return Err(format!("PxCreatePhysics failed: {}", errors().join("; ")));
        }
        Ok(Sdk { foundation, physics })
    }).as_ref().map_err(|e| e.clone())
}

/// counts the contact points of every touching shape pair PhysX reports (onContact, called from
/// fetchResults on the stepping thread); the user data is the world's counter
unsafe extern "C" fn count_contact_points(user: *mut c_void, _header: *const PxContactPairHeader,
                                          pairs: *const PxContactPair, count: u32) {
    let points = unsafe { &*(user as *const AtomicUsize) };
    let pairs = unsafe { std::slice::from_raw_parts(pairs, count as usize) };
    let sum: usize = pairs.iter().map(|p| p.contactCount as usize).sum();
    points.fetch_add(sum, Ordering::Relaxed);
}

/// the simulation filter of scenes with contacts: every shape pair collides (as PhysX's default
/// shader lets them, no groups here) and reports its touch, found or kept, with its contact
/// points, so that `count_contact_points` sees each touching pair once a simulate call
unsafe extern "C" fn report_touching_pairs(info: *mut FilterShaderCallbackInfo) -> PxFilterFlags {
    unsafe {
        *(*info).pairFlags = PxPairFlags::ContactDefault | PxPairFlags::NotifyTouchFound
            | PxPairFlags::NotifyTouchPersists | PxPairFlags::NotifyContactPoints;
    }
    PxFilterFlags::empty()
}

impl Engine for PhysX {
    fn name(&self) -> &'static str {
        "physx"
    }
    fn version(&self) -> String {
        let v = PHYSX_VERSION;
        let number = format!("{}.{}.{}", v >> 24, (v >> 16) & 0xff, (v >> 8) & 0xff);
        match sdk() {
            Ok(_) => format!("{number} (float; {CRATE}, CPU only)"),
            Err(e) => format!("{number} (float; {CRATE}; did not start: {e})"),
        }
    }
    fn variants(&self) -> &'static [&'static str] {
        &["pgs", "tgs", "iterations-10"]
    }
    fn settings(&self, variant: &str) -> Vec<Setting> {
        let solver_type = match variant {
            "tgs" => setting("solverType", "eTGS (default ePGS)",
                             "PhysX's temporal Gauss-Seidel solver: each position iteration is a \
                              substep of the solve"),
            _ => setting("solverType", "ePGS (PhysX's default, PxSceneDesc)",
                         "PhysX's projected Gauss-Seidel solver"),
        };
        let iterations = if variant == "iterations-10" {
            setting("solver iterations (setSolverIterationCounts)",
                    "10 position, 1 velocity, every dynamic body (default 4 and 1)",
                    "equal iterations: PhysX's position iterations are its biased solve passes, \
                     the nearest to the other engines' 10 velocity iterations; its velocity \
                     iterations (unbiased passes after them) stay at 1")
        } else {
            setting("solver iterations (setSolverIterationCounts)",
                    "4 position, 1 velocity (PhysX's defaults)", "the engine's defaults")
        };
        vec![
            solver_type,
            iterations,
            setting("step", "one simulate(dt) and fetchResults(true) a step",
                    "the scene's dt is the step, as for every peer"),
            setting("sleeping", "sleepThreshold 0 on every dynamic body (default 5e-3 m²/s²)",
                    "sleeping off in every engine: PhysX has no switch for it; with a threshold \
                     of 0 its energy test always passes, so the wake counter is reset every step \
                     and no body falls asleep (stabilization stays off, PhysX's default)"),
            setting("bounceThresholdVelocity", RESTITUTION_THRESHOLD,
                    "the scene's 0.1 m/s (default 0.2 × the tolerance speed = 2 m/s)"),
            setting("friction combine", "eMULTIPLY; each material's static and dynamic \
                     friction √μ of its body's μ", "PhysX combines by average (its default), \
                     min, multiply or max, none of them √(μa μb); the product of the two roots \
                     is that rule exactly, for every pair (the in-process Bullet adapter does the \
                     same), and static friction = dynamic friction = the scene's μ"),
            setting("restitution combine", "eMAX (default eAVERAGE)",
                    "the scene's max(ea, eb)"),
            setting("contactOffset / restOffset", "0.02 m / 0 m on every shape (PhysX's \
                     defaults)", "contacts form when two shapes come within 4 cm (2 cm each, \
                     speculative); surfaces rest touching, as the scene's touching boxes do"),
            setting("maxDepenetrationVelocity", "unlimited (PhysX's default, 1e32)",
                    "the solver's push-out speed is not clamped"),
            setting("maxAngularVelocity", MAXIMUM_ANGULAR_SPEED,
                    "rad/s; default 100 rad/s would clamp a spinning body silently: the scene \
                     format allows 1e5"),
            setting("maxLinearVelocity", "PhysX's default for a dynamic body (1e16 m/s)",
                    "already no clamp within the scene format's 1e5 m/s"),
            setting("linear / angular damping", "0 / 0 (defaults 0 / 0.05)",
                    "the scenes have no damping"),
            setting("eENABLE_GYROSCOPIC_FORCES", "on (default off)",
                    "a free body's angular momentum, not its angular velocity, is constant: \
                     without it the tumbling box cannot flip"),
            setting("mass properties", "setMass, setMassSpaceInertiaTensor (the principal \
                     moments), setCMassLocalPose identity, from the scene",
                    "every engine integrates the same body; PhysX computes none (no density)"),
            setting("plane", "PxPlaneGeometry with a shape pose turning its +x normal to the \
                     body's local +y (a quarter turn about z)",
                    "PhysX's own infinite half space, solid below the body's local y = 0"),
            setting("friction model", "ePATCH with eIMPROVED_PATCH_FRICTION, frictionOffset\
                     Threshold 0.04 m, frictionCorrelationDistance 0.025 m (PhysX's defaults)",
                    "the engine's defaults"),
            setting("contact generation", "PCM (eENABLE_PCM), discrete, no CCD or speculative \
                     CCD, broad phase ePABP (PhysX's defaults)",
                    "continuous collision is each engine's default in the tunnelling scenes"),
            setting("shape flags", "simulation, scene query and visualization (PhysX's \
                     defaults)", "the engine's defaults: its scene-query tree is kept up to \
                     date in the step"),
            setting("CPU dispatcher", "PxDefaultCpuDispatcherCreate(0): no worker threads",
                    "every worker steps on one thread: with no workers PhysX runs every task on \
                     the thread that calls simulate; no GPU (the crate builds with \
                     DISABLE_CUDA_PHYSX)"),
            setting("instruction set", "physx-sys 0.11.5's build script through the cc crate: clang++ \
                     -O3 (the release profile) -ffunction-sections -fdata-sections -fPIC -m64 \
                     -std=c++14 -w -fno-strict-aliasing; NDEBUG, PX_PHYSX_STATIC_LIB, \
                     DISABLE_CUDA_PHYSX, PX_SUPPORT_PVD=1 (none connected); no -march",
                    "as the crate builds it: x86-64 baseline, PhysX's SSE2 vector path (no \
                     SSE4, AVX or FMA instructions in the library); a release build, so \
                     PhysX's checked-build parameter tests and warnings are compiled out"),
            setting("planar scenes", "run free in 3D (no lock flags)",
                    "as the other 3D workers run them"),
            setting("collisions off", "bodies carry no shapes",
                    "no broad or narrow phase runs; mass and inertia are set explicitly"),
            setting("springs", "external force and torque at the attachment points, from the \
                     state at the start of each step, applied (eFORCE) before every simulate \
                     call of the step", "the same method as the other peers' springs; PhysX \
                     clears forces after each simulate call"),
            setting("impulses", "PxRigidBodyExt::addForceAtPos, eIMPULSE",
                    "applied at the next simulate call"),
            setting("contact reports", "on scenes with contacts: a filter shader asks for \
                     eNOTIFY_TOUCH_FOUND, eNOTIFY_TOUCH_PERSISTS and eNOTIFY_CONTACT_POINTS on \
                     every pair; onContact sums each touching pair's contactCount",
                    "the contact points of the step's last simulate call; PhysX calls onContact \
                     in fetchResults, inside the timed step"),
            setting("errors", "an error callback on the foundation; any report but debug \
                     information or a performance warning, a failed simulate or fetchResults, \
                     or a full contact memory pool (maxNbContactDataBlocks, default 65536 × \
                     16 KB) ends the run as an error", "PhysX's answer would be wrong"),
        ]
    }
    fn unsupported(&self, scene: &Scene, _variant: &str) -> Option<String> {
        scene.particles_unsupported("PhysX")
    }
    fn not_applicable(&self, scene: &Scene, variant: &str) -> Option<String> {
        scene.iterations_not_applicable(variant, "solver iterations matter only with contacts")
    }
    /// substeps: simulate(dt/N) and fetchResults N times a step; iterations: the position
    /// iterations of every dynamic body (setSolverIterationCounts, default 4; velocity stays 1)
    fn tune(&self, _variant: &str, knobs: &Knobs) -> Result<Vec<Setting>, String> {
        let mut s = Vec::new();
        if knobs.substeps > 0 {
            s.push(setting("simulate calls a step", knobs.substeps,
                           "the sweep's substeps (--sweep-substeps): N calls of simulate(dt/N) \
                            and fetchResults(true) a step, the spring forces applied before \
                            each"));
        }
        if knobs.iterations > 0 {
            s.push(setting("position iterations", knobs.iterations,
                           "the sweep's iterations (--sweep-iterations): setSolverIteration\
                            Counts(N, 1) on every dynamic body (default 4 position, 1 \
                            velocity)"));
        }
        Ok(s)
    }
    fn create(&self, scene: &Scene, variant: &str, knobs: &Knobs)
        -> Result<Box<dyn World>, String> {
        Ok(Box::new(build(scene, variant, knobs)?))
    }
}

/// one world: a scene of its own with its dispatcher, materials and actors
fn build(scene: &Scene, variant: &str, knobs: &Knobs) -> Result<PhysxWorld, String> {
    let physics = sdk()?.physics;
    let errors_before = errors().len();
    unsafe {
        let dispatcher = phys_PxDefaultCpuDispatcherCreate(
            0, null_mut(), PxDefaultCpuDispatcherWaitForWorkMode::WaitForWork, 0);
        if dispatcher.is_null() {
            return Err("PxDefaultCpuDispatcherCreate failed".into());
        }
        let mut desc = PxSceneDesc_new(PxPhysics_getTolerancesScale(physics));
        desc.gravity = vec3(scene.gravity);
        desc.solverType = solver(variant);
        desc.bounceThresholdVelocity = RESTITUTION_THRESHOLD as f32;
        desc.cpuDispatcher = dispatcher.cast();
        // a scene with contacts counts their points; any other runs PhysX's default shader
        let counts_contacts = scene.has_contacts();
        let points = Box::new(AtomicUsize::new(0));
        let events = if counts_contacts {
            let info = SimulationEventCallbackInfo {
                collision_callback: Some(count_contact_points),
                collision_user_data: &*points as *const AtomicUsize as *mut c_void,
                ..Default::default()
            };
            let events = create_simulation_event_callbacks(&info);
            desc.simulationEventCallback = events;
            // the wrapper keeps the first shader it is given for the whole process (a static):
            // this worker only ever gives it this one
            enable_custom_filter_shader(&mut desc, report_touching_pairs, 0);
            events
        } else {
            desc.filterShader = get_default_simulation_filter_shader();
            null_mut()
        };
        let max_blocks = desc.maxNbContactDataBlocks;
        let px_scene = PxPhysics_createScene_mut(physics, &desc);
        if px_scene.is_null() {
            PxDefaultCpuDispatcher_release_mut(dispatcher);
            if !events.is_null() {
                destroy_simulation_event_callbacks(events);
            }
            return Err(format!("PxPhysics::createScene failed: {}",
                               errors()[errors_before..].join("; ")));
        }
        let mut world = PhysxWorld {
            scene: px_scene,
            dispatcher,
            events,
            materials: Vec::new(),
            actors: Vec::with_capacity(scene.bodies.len()),
            dt: scene.dt as f32,
            substeps: knobs.substeps.max(1),
            held: Vec::new(),
            points,
            counts_contacts,
            errors_before,
            failed: None,
            max_blocks,
            simulate_calls: 0,
        };
        let mut by_material: HashMap<(u64, u64), *mut PxMaterial> = HashMap::new();
        let iterations = position_iterations(variant, knobs);
        for b in &scene.bodies {
            let material = *by_material.entry((b.friction.to_bits(), b.restitution.to_bits()))
                .or_insert_with(|| {
                    let m = make_material(physics, b);
                    world.materials.push(m);
                    m
                });
            if material.is_null() {
                return Err(format!("PhysX refused the material of body '{}'", b.name));
            }
            let pose = transform(b.position, b.orientation);
            let dynamic = b.mass > 0.0;
            let actor: *mut PxRigidActor = if dynamic {
                PxPhysics_createRigidDynamic_mut(physics, &pose).cast()
            } else {
                PxPhysics_createRigidStatic_mut(physics, &pose).cast()
            };
            if actor.is_null() {
                return Err(format!("PhysX refused body '{}'", b.name));
            }
            world.actors.push(actor);
            if scene.collisions {
                let flags = PxShapeFlags::SimulationShape | PxShapeFlags::SceneQueryShape
                    | PxShapeFlags::Visualization;
                let shape = match b.shape {
                    Shape::Box { half_extents: h } => {
                        let g = PxBoxGeometry_new(h[0] as f32, h[1] as f32, h[2] as f32);
                        PxRigidActorExt_createExclusiveShape_1(
                            actor, &g as *const PxBoxGeometry as *const PxGeometry, material, flags)
                    }
                    Shape::Sphere { radius } => {
                        let g = PxSphereGeometry_new(radius as f32);
                        PxRigidActorExt_createExclusiveShape_1(
                            actor, &g as *const PxSphereGeometry as *const PxGeometry, material,
                            flags)
                    }
                    Shape::Plane => {
                        let g = PxPlaneGeometry_new();
                        let s = PxRigidActorExt_createExclusiveShape_1(
                            actor, &g as *const PxPlaneGeometry as *const PxGeometry, material,
                            flags);
                        if !s.is_null() {
                            PxShape_setLocalPose_mut(s, &plane_local_pose());
                        }
                        s
                    }
                };
                if shape.is_null() {
                    return Err(format!("PhysX refused the shape of body '{}'", b.name));
                }
            }
            if dynamic {
                let body: *mut PxRigidBody = actor.cast();
                let rigid: *mut PxRigidDynamic = actor.cast();
                PxRigidBody_setMass_mut(body, b.mass as f32);
                PxRigidBody_setMassSpaceInertiaTensor_mut(body, &vec3(b.principal_inertia()));
                PxRigidBody_setCMassLocalPose_mut(body, &transform([0.0; 3], [1.0, 0.0, 0.0, 0.0]));
                PxRigidBody_setLinearDamping_mut(body, 0.0);
                PxRigidBody_setAngularDamping_mut(body, 0.0);
                PxRigidBody_setMaxAngularVelocity_mut(body, MAXIMUM_ANGULAR_SPEED);
                PxRigidBody_setRigidBodyFlag_mut(body, PxRigidBodyFlag::EnableGyroscopicForces,
                                                 true);
                PxRigidDynamic_setSleepThreshold_mut(rigid, 0.0);
                PxRigidDynamic_setSolverIterationCounts_mut(rigid, iterations,
                                                            DEFAULT_VELOCITY_ITERATIONS);
            }
            if !PxScene_addActor_mut(px_scene, actor.cast(), null()) {
                return Err(format!("PhysX did not add body '{}' to the scene", b.name));
            }
            if dynamic {
                let rigid: *mut PxRigidDynamic = actor.cast();
                PxRigidDynamic_setLinearVelocity_mut(rigid, &vec3(b.linear_velocity), true);
                PxRigidDynamic_setAngularVelocity_mut(rigid, &vec3(b.angular_velocity), true);
            }
        }
        if let Some(e) = world.error() {
            return Err(e);
        }
        Ok(world)
    }
}

unsafe fn make_material(physics: *mut PxPhysics, b: &Body) -> *mut PxMaterial {
    let mu = material_friction(b.friction);
    let m = unsafe { PxPhysics_createMaterial_mut(physics, mu, mu, b.restitution as f32) };
    if !m.is_null() {
        unsafe {
            PxMaterial_setFrictionCombineMode_mut(m, PxCombineMode::Multiply);
            PxMaterial_setRestitutionCombineMode_mut(m, PxCombineMode::Max);
        }
    }
    m
}

struct PhysxWorld {
    scene: *mut PxScene,
    dispatcher: *mut PxDefaultCpuDispatcher,
    events: *mut PxSimulationEventCallback, // null on a scene without contacts
    materials: Vec<*mut PxMaterial>,
    actors: Vec<*mut PxRigidActor>, // scene order
    dt: f32,
    substeps: usize, // simulate calls a step: 1, or a sweep's substeps
    // the step's external forces and torques about the centre of mass, applied before each of
    // its simulate calls (PhysX clears them after every call)
    held: Vec<(usize, PxVec3, PxVec3)>,
    points: Box<AtomicUsize>, // the contact callback's count for the last simulate call
    counts_contacts: bool,
    errors_before: usize, // PhysX's reports before this world was built are not its own
    failed: Option<String>,
    max_blocks: u32,
    simulate_calls: u64,
}

impl Drop for PhysxWorld {
    fn drop(&mut self) {
        unsafe {
            for &actor in &self.actors {
                PxRigidActor_release_mut(actor);
            }
            PxScene_release_mut(self.scene);
            for &m in &self.materials {
                PxRefCounted_release_mut(m.cast());
            }
            PxDefaultCpuDispatcher_release_mut(self.dispatcher);
            if !self.events.is_null() {
                destroy_simulation_event_callbacks(self.events);
            }
        }
    }
}

impl World for PhysxWorld {
    fn step(&mut self) {
        let h = self.dt / self.substeps as f32;
        for _ in 0..self.substeps {
            unsafe {
                for (i, force, torque) in &self.held {
                    let body: *mut PxRigidBody = self.actors[*i].cast();
                    PxRigidBody_addForce_mut(body, force, PxForceMode::Force, true);
                    PxRigidBody_addTorque_mut(body, torque, PxForceMode::Force, true);
                }
                // the count is the last simulate call's
                self.points.store(0, Ordering::Relaxed);
                let simulated = PxScene_simulate_mut(self.scene, h, null_mut(), null_mut(), 0,
                                                     true);
                let mut error_state = 0u32;
                let fetched = PxScene_fetchResults_mut(self.scene, true, &mut error_state);
                self.simulate_calls += 1;
                if (!simulated || !fetched || error_state != 0) && self.failed.is_none() {
                    self.failed = Some(format!("PhysX's simulate ({simulated}) or fetchResults \
                                                ({fetched}, error state {error_state}) failed"));
                }
            }
        }
        self.held.clear();
    }
    fn state(&self, body: usize) -> State {
        unsafe {
            let actor = self.actors[body];
            let pose = PxRigidActor_getGlobalPose(actor);
            let d = |a: PxVec3| [a.x as f64, a.y as f64, a.z as f64];
            let (v, w) = match PxActor_getType(actor.cast()) {
                PxActorType::RigidDynamic => {
                    let b: *const PxRigidBody = actor.cast();
                    (d(PxRigidBody_getLinearVelocity(b)), d(PxRigidBody_getAngularVelocity(b)))
                }
                _ => ([0.0; 3], [0.0; 3]),
            };
            let q = pose.q;
            State {
                position: d(pose.p),
                orientation: [q.w as f64, q.x as f64, q.y as f64, q.z as f64],
                linear_velocity: v,
                angular_velocity: w,
            }
        }
    }
    fn add_force_at_point(&mut self, body: usize, force: [f64; 3], point: [f64; 3]) {
        // the centre of mass is the actor's origin (setCMassLocalPose identity)
        let c = self.state(body).position;
        let r = [point[0] - c[0], point[1] - c[1], point[2] - c[2]];
        let torque = [r[1] * force[2] - r[2] * force[1], r[2] * force[0] - r[0] * force[2],
                      r[0] * force[1] - r[1] * force[0]];
        self.held.push((body, vec3(force), vec3(torque)));
    }
    fn apply_impulse(&mut self, body: usize, impulse: [f64; 3], point: [f64; 3]) {
        unsafe {
            PxRigidBodyExt_addForceAtPos(self.actors[body].cast(), &vec3(impulse), &vec3(point),
                                         PxForceMode::Impulse, true)
        };
    }
    fn error(&self) -> Option<String> {
        if let Some(e) = errors().get(self.errors_before) {
            return Some(e.clone());
        }
        if let Some(e) = &self.failed {
            return Some(e.clone());
        }
        let used = unsafe { PxScene_getMaxNbContactDataBlocksUsed(self.scene) };
        (used >= self.max_blocks).then(|| {
            format!("PhysX used all {} of its 16 KB contact and constraint blocks: contacts were \
                     dropped", self.max_blocks)
        })
    }
    /// the contact points of every touching shape pair in the step's last simulate call, as
    /// PhysX reported them to the contact callback
    fn contact_points(&self) -> Option<usize> {
        self.counts_contacts.then(|| self.points.load(Ordering::Relaxed))
    }
}

fn main() {
    physbench_worker::main(&PhysX);
}

#[cfg(test)]
mod tests {
    use super::*;
    use physbench_worker::checks;

    // PhysX's one foundation is shared by the process: the tests take turns
    static TURN: Mutex<()> = Mutex::new(());

    fn turn() -> std::sync::MutexGuard<'static, ()> {
        TURN.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn body(name: &str, shape: Shape, mass: f64, position: [f64; 3]) -> Body {
        Body { name: name.into(), shape, mass, position, orientation: [1.0, 0.0, 0.0, 0.0],
               linear_velocity: [0.0; 3], angular_velocity: [0.0; 3], friction: 0.5,
               restitution: 0.0 }
    }

    fn cube(y: f64) -> Body {
        body("cube", Shape::Box { half_extents: [0.5; 3] }, 1.0, [0.0, y, 0.0])
    }

    fn ground() -> Body {
        body("ground", Shape::Plane, 0.0, [0.0; 3])
    }

    fn scene(bodies: Vec<Body>, dt: f64, duration: f64) -> Scene {
        let probe_bodies = (0..bodies.len()).filter(|&i| bodies[i].mass > 0.0).collect();
        Scene { name: "test".into(), gravity: [0.0, -9.81, 0.0], dt, duration, planar: false,
                collisions: true, bodies, springs: Vec::new(), impulses: Vec::new(),
                has_particles: false, probe_bodies, probe_interval: dt }
    }

    fn run(world: &mut PhysxWorld, steps: usize) {
        for _ in 0..steps {
            world.step();
        }
        assert_eq!(world.error(), None);
    }

    #[test]
    fn friction_mixes_by_the_scenes_pair_rule() {
        let _t = turn();
        for v in ["pgs", "tgs"] {
            checks::pair_friction(&PhysX, v).unwrap();
        }
    }
    #[test]
    fn restitution_mixes_by_the_scenes_pair_rule() {
        let _t = turn();
        for v in ["pgs", "tgs"] {
            checks::pair_restitution(&PhysX, v).unwrap();
        }
    }
    #[test]
    fn the_scenes_mass_and_inertia_reach_the_engine() {
        let _t = turn();
        for v in ["pgs", "tgs"] {
            checks::mass_and_inertia(&PhysX, v).unwrap();
        }
    }
    #[test]
    fn the_plane_is_the_bodys_y_zero_surface() {
        let _t = turn();
        for v in ["pgs", "tgs"] {
            checks::rests_on_the_plane(&PhysX, v).unwrap();
        }
    }
    #[test]
    fn the_substeps_knob_reaches_the_step() {
        let _t = turn();
        for n in [1, 4] {
            checks::substeps_reach_the_step(&PhysX, "pgs", n).unwrap();
        }
    }

    #[test]
    fn a_box_touching_the_plane_stays_there() {
        let _t = turn();
        for v in ["pgs", "tgs"] {
            let s = scene(vec![ground(), cube(0.5)], 1.0 / 60.0, 1.0);
            let mut world = build(&s, v, &Knobs::default()).unwrap();
            run(&mut world, 60);
            let st = world.state(1);
            assert!((st.position[1] - 0.5).abs() < 2e-3 && st.position[0].abs() < 1e-3,
                    "{v}: the cube moved to {:?}", st.position);
        }
    }

    #[test]
    fn a_box_below_the_plane_is_pushed_up() {
        let _t = turn();
        // 10 cm deep under gravity: the plane pushes it out along its normal +y, to rest on the
        // surface (a plane facing −y, or solid above, would let it fall or push it down)
        let s = scene(vec![ground(), cube(0.4)], 1.0 / 60.0, 1.0);
        let mut world = build(&s, "pgs", &Knobs::default()).unwrap();
        run(&mut world, 1);
        assert!(world.state(1).position[1] > 0.4, "the first step moved it to {:?}",
                world.state(1).position);
        run(&mut world, 59);
        let st = world.state(1);
        assert!((st.position[1] - 0.5).abs() < 0.01, "the cube went to {:?}", st.position);
        assert!(st.position[0].abs() < 0.01 && st.position[2].abs() < 0.01, "{st:?}");
    }

    #[test]
    fn a_turned_plane_faces_its_bodys_local_y() {
        let _t = turn();
        // turned a quarter about z, the plane's normal is world −x: a cube pressed against it
        // along +x by gravity rests at x = −0.5
        let half = std::f64::consts::FRAC_PI_4;
        let mut plane = ground();
        plane.orientation = [half.cos(), 0.0, 0.0, half.sin()];
        let mut c = cube(0.0);
        c.position = [-0.5, 0.0, 0.0];
        let mut s = scene(vec![plane, c], 1.0 / 60.0, 1.0);
        s.gravity = [9.81, 0.0, 0.0];
        let mut world = build(&s, "pgs", &Knobs::default()).unwrap();
        run(&mut world, 60);
        let x = world.state(1).position[0];
        assert!((x + 0.5).abs() < 2e-3, "the cube went to x = {x}");
    }

    #[test]
    fn mass_and_inertia_read_back_as_the_scenes() {
        let _t = turn();
        let mut b = body("b", Shape::Box { half_extents: [0.3, 0.2, 0.1] }, 2.0, [0.0, 3.0, 0.0]);
        b.orientation = [0.8, 0.6, 0.0, 0.0];
        let inertia = b.principal_inertia();
        let s = scene(vec![ground(), b], 1.0 / 60.0, 1.0);
        let world = build(&s, "pgs", &Knobs::default()).unwrap();
        unsafe {
            let rb: *const PxRigidBody = world.actors[1].cast();
            assert_eq!(PxRigidBody_getMass(rb), 2.0);
            let i = PxRigidBody_getMassSpaceInertiaTensor(rb);
            for (got, want) in [i.x, i.y, i.z].iter().zip(inertia) {
                assert!((*got as f64 - want).abs() < 1e-6 * want, "{got} against {want}");
            }
            let c = PxRigidBody_getCMassLocalPose(rb);
            assert_eq!((c.p.x, c.p.y, c.p.z, c.q.w), (0.0, 0.0, 0.0, 1.0));
        }
    }

    #[test]
    fn the_solver_settings_reach_every_dynamic_body() {
        let _t = turn();
        let s = scene(vec![ground(), cube(0.5), cube(1.5)], 1.0 / 60.0, 1.0);
        for (variant, knobs, position) in [("pgs", Knobs::default(), 4), ("tgs", Knobs::default(), 4),
                                           ("iterations-10", Knobs::default(), 10),
                                           ("pgs", Knobs { iterations: 7, substeps: 0 }, 7)] {
            let world = build(&s, variant, &knobs).unwrap();
            unsafe {
                assert_eq!(PxScene_getSolverType(world.scene), solver(variant));
                assert_eq!(PxScene_getBounceThresholdVelocity(world.scene), 0.1);
                for &a in &world.actors[1..] {
                    let (mut p, mut v) = (0u32, 0u32);
                    PxRigidDynamic_getSolverIterationCounts(a.cast(), &mut p, &mut v);
                    assert_eq!((p, v), (position, 1), "{variant} {knobs:?}");
                    assert_eq!(PxRigidDynamic_getSleepThreshold(a.cast()), 0.0);
                    assert_eq!(PxRigidBody_getMaxAngularVelocity(a.cast()), 1.0e5);
                    assert_eq!(PxRigidBody_getAngularDamping(a.cast()), 0.0);
                    assert!(PxRigidBody_getRigidBodyFlags(a.cast())
                        .contains(PxRigidBodyFlags::EnableGyroscopicForces));
                }
            }
        }
    }

    #[test]
    fn the_default_solver_is_pgs() {
        let _t = turn();
        // the variant named first is PhysX's own default, read from a scene left at it
        assert_eq!(PhysX.variants()[0], "pgs");
        unsafe {
            let physics = sdk().unwrap().physics;
            let desc = PxSceneDesc_new(PxPhysics_getTolerancesScale(physics));
            assert_eq!(desc.solverType, PxSolverType::Pgs);
            assert!((desc.bounceThresholdVelocity - 2.0).abs() < 1e-6);
        }
    }

    #[test]
    fn the_materials_multiply_roots_and_take_the_larger_restitution() {
        let _t = turn();
        let mut a = cube(0.5);
        a.friction = 0.25;
        a.restitution = 0.3;
        let mut g = ground();
        g.friction = 1.0;
        let s = scene(vec![g, a], 1.0 / 60.0, 1.0);
        let world = build(&s, "pgs", &Knobs::default()).unwrap();
        assert_eq!(world.materials.len(), 2);
        unsafe {
            let m = world.materials[1];
            assert_eq!(PxMaterial_getStaticFriction(m), 0.5);
            assert_eq!(PxMaterial_getDynamicFriction(m), 0.5);
            assert!((PxMaterial_getRestitution(m) - 0.3).abs() < 1e-7);
            assert_eq!(PxMaterial_getFrictionCombineMode(m), PxCombineMode::Multiply);
            assert_eq!(PxMaterial_getRestitutionCombineMode(m), PxCombineMode::Max);
        }
    }

    #[test]
    fn the_substeps_knob_runs_that_many_simulate_calls() {
        let _t = turn();
        let s = scene(vec![ground(), cube(0.5)], 1.0 / 60.0, 1.0);
        for n in [1, 3, 8] {
            let mut world = build(&s, "pgs", &Knobs { iterations: 0, substeps: n }).unwrap();
            run(&mut world, 5);
            assert_eq!(world.simulate_calls, 5 * n as u64);
        }
    }

    #[test]
    fn a_force_acts_over_every_substep_of_its_step() {
        let _t = turn();
        // 2 N on 1 kg for one step of 0.1 s: Δv = 0.2 m/s whatever the substeps; a force PhysX
        // cleared after the first of 4 calls would give 0.05
        let mut s = scene(vec![cube(5.0)], 0.1, 0.1);
        s.gravity = [0.0; 3];
        for n in [1, 4] {
            let mut world = build(&s, "pgs", &Knobs { iterations: 0, substeps: n }).unwrap();
            world.add_force_at_point(0, [2.0, 0.0, 0.0], [0.0, 5.0, 0.0]);
            run(&mut world, 1);
            let v = world.state(0).linear_velocity[0];
            assert!((v - 0.2).abs() < 1e-5, "{n} substeps: v = {v}");
            // the next step has no force: it keeps its speed
            run(&mut world, 1);
            assert!((world.state(0).linear_velocity[0] - 0.2).abs() < 1e-5);
        }
    }

    #[test]
    fn bodies_never_sleep() {
        let _t = turn();
        // at rest on the plane for 10 s, far past PhysX's 0.4 s wake counter
        let s = scene(vec![ground(), cube(0.5)], 1.0 / 60.0, 10.0);
        let mut world = build(&s, "pgs", &Knobs::default()).unwrap();
        run(&mut world, 600);
        assert!(!unsafe { PxRigidDynamic_isSleeping(world.actors[1].cast()) });
        // and it still answers an impulse at once
        world.apply_impulse(1, [0.0, 5.0, 0.0], [0.0, 0.5, 0.0]);
        run(&mut world, 1);
        assert!(world.state(1).linear_velocity[1] > 4.0);
    }

    #[test]
    fn a_resting_box_reports_its_contact_points() {
        let _t = turn();
        let s = scene(vec![ground(), cube(0.5)], 1.0 / 60.0, 1.0);
        for n in [1, 4] {
            let mut world = build(&s, "pgs", &Knobs { iterations: 0, substeps: n }).unwrap();
            run(&mut world, 10);
            // a face on the plane: its four corners, the last simulate call's only
            assert_eq!(world.contact_points(), Some(4), "{n} substeps");
        }
        // one body: nothing to count
        let single = scene(vec![cube(0.5)], 1.0 / 60.0, 1.0);
        assert_eq!(build(&single, "pgs", &Knobs::default()).unwrap().contact_points(), None);
    }

    #[test]
    fn without_collisions_bodies_pass_through() {
        let _t = turn();
        let mut s = scene(vec![ground(), cube(0.5)], 1.0 / 60.0, 1.0);
        s.collisions = false;
        let mut world = build(&s, "pgs", &Knobs::default()).unwrap();
        run(&mut world, 60);
        // a free fall of 1 s: 4.9 m and more
        assert!(world.state(1).position[1] < -4.0);
        assert_eq!(world.contact_points(), None);
    }

    #[test]
    fn an_error_physx_reports_makes_the_run_an_error() {
        let _t = turn();
        let s = scene(vec![ground(), cube(0.5)], 1.0 / 60.0, 1.0);
        let world = build(&s, "pgs", &Knobs::default()).unwrap();
        assert_eq!(world.error(), None);
        // a physics object of another version is refused, through the foundation's callback
        let refused = unsafe {
            let scale = PxTolerancesScale { length: SCALE_LENGTH, speed: SCALE_SPEED };
            phys_PxCreatePhysics(PHYSX_VERSION + (1 << 8), sdk().unwrap().foundation, &scale,
                                 false, null_mut(), null_mut())
        };
        assert!(refused.is_null());
        let e = world.error().expect("PhysX's report reaches the world");
        assert!(e.contains("InvalidParameter") && e.contains("Wrong version"), "{e}");
        // a world built afterwards does not inherit it
        assert_eq!(build(&s, "pgs", &Knobs::default()).unwrap().error(), None);
    }

    #[test]
    fn particles_are_refused_and_the_version_is_the_librarys() {
        let _t = turn();
        let mut s = scene(vec![cube(0.5)], 1.0 / 60.0, 1.0);
        s.has_particles = true;
        assert!(PhysX.unsupported(&s, "pgs").unwrap().contains("PhysX"));
        assert!(PhysX.version().starts_with("5.1.3 (float"), "{}", PhysX.version());
    }

    #[test]
    fn iterations_10_makes_no_row_without_contacts() {
        let s = scene(vec![cube(0.5)], 1.0 / 60.0, 1.0);
        assert!(PhysX.not_applicable(&s, "iterations-10").is_some());
        assert!(PhysX.not_applicable(&s, "tgs").is_none());
        let c = scene(vec![ground(), cube(0.5)], 1.0 / 60.0, 1.0);
        assert!(PhysX.not_applicable(&c, "iterations-10").is_none());
    }
}
