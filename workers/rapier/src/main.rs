//! Rapier (rapier3d, single precision) as a harness worker: docs/worker-protocol.md.

use physbench_worker::{setting, Engine, Knobs, Scene, Setting, Shape, State, World};
use rapier3d::na::Unit;
use rapier3d::prelude::*;

struct Rapier;

// compiled for this machine's instruction set (-C target-cpu=native reaches AVX2 on every machine
// this runs on; the default target never does)
const NATIVE: bool = cfg!(target_feature = "avx2");

/// The SIMD target features this build was compiled with.
fn target_features() -> String {
    let features = [("avx512f", cfg!(target_feature = "avx512f")), ("avx2", cfg!(target_feature = "avx2")),
                    ("fma", cfg!(target_feature = "fma")), ("sse4.2", cfg!(target_feature = "sse4.2"))];
    let on: Vec<&str> = features.iter().filter(|(_, on)| *on).map(|(name, _)| *name).collect();
    if on.is_empty() { "SSE2".into() } else { on.join(", ") }
}

// equal iterations: Rapier's solver iterations are substeps of its soft-step solver (one PGS and
// one stabilisation pass each), the nearest equivalent of 10 velocity iterations
const EQUAL_ITERATIONS: usize = 10;

impl Engine for Rapier {
    fn name(&self) -> &'static str {
        "rapier"
    }
    fn version(&self) -> String {
        format!("{} (f32)", rapier3d::VERSION)
    }
    fn variants(&self) -> &'static [&'static str] {
        // the build for this machine's instruction set (physbench-rapier-native, built with
        // -C target-cpu=native) runs the defaults under a name that says so
        if NATIVE { &["default-native"] } else { &["default", "iterations-10"] }
    }
    fn settings(&self, variant: &str) -> Vec<Setting> {
        let mut s = vec![
            if NATIVE {
                setting("instruction set",
                        format!("this machine's (-C target-cpu=native): {}, f32", target_features()),
                        "the native-instruction-set comparison beside rtp's native build; the \
                         crate's default features")
            } else {
                setting("instruction set",
                        "x86-64 baseline: SSE2 (Rust's default target; rapier3d's default \
                         features), f32",
                        "the crate's default features; rtp's -x86-64 variants are the \
                         equal-instruction-set comparison")
            },
            setting("sleeping", "off (can_sleep false on every body)",
                    "sleeping off in every engine"),
            setting("mass properties", "from the scene, colliders at density 0",
                    "every engine integrates the same body"),
            setting("friction combine rule", "GeometricMean (default Average)",
                    "the scene's pair rule: √(μa μb)"),
            setting("restitution combine rule", "Max (default Average)",
                    "the scene's pair rule: max(ea, eb)"),
            setting("restitution threshold", "none (Rapier has none)",
                    "the scene's 0.1 m/s cannot be set: restitution applies at every speed"),
            setting("springs", "external force at the attachment points, from the state at the \
                     start of each step", "the same method as the other peers' springs"),
            setting("plane", "a HalfSpace collider, normal the body's local +y",
                    "the scene's plane is its body's local y = 0 surface, solid below"),
        ];
        s.push(setting("num_solver_iterations on springs without contacts", 1,
                       "Rapier's iterations are substeps; the spring force is held over the step, \
                        so one substep makes it semi-implicit Euler, as for the other peers"));
        if variant == "iterations-10" {
            s.push(setting("num_solver_iterations", EQUAL_ITERATIONS,
                           "equal iterations (default 4): Rapier's iterations are substeps"));
        }
        s
    }
    fn unsupported(&self, scene: &Scene, _variant: &str) -> Option<String> {
        scene.particles_unsupported("Rapier")
    }
    fn not_applicable(&self, scene: &Scene, variant: &str) -> Option<String> {
        scene.iterations_not_applicable(variant, "solver iterations matter only with contacts")
    }
    /// substeps: num_solver_iterations, which are the substeps of Rapier's soft-step solver;
    /// iterations: num_internal_pgs_iterations, the PGS passes within each
    fn tune(&self, _variant: &str, knobs: &Knobs) -> Result<Vec<Setting>, String> {
        let mut s = Vec::new();
        if knobs.substeps > 0 {
            s.push(setting("num_solver_iterations", knobs.substeps,
                           "the sweep's substeps (--sweep-substeps): Rapier's solver iterations \
                            are the substeps of its soft-step solver"));
        }
        if knobs.iterations > 0 {
            s.push(setting("num_internal_pgs_iterations", knobs.iterations,
                           "the sweep's iterations (--sweep-iterations): the PGS passes of each \
                            substep (default 1)"));
        }
        Ok(s)
    }
    fn create(&self, scene: &Scene, variant: &str, knobs: &Knobs)
        -> Result<Box<dyn World>, String> {
        let mut world = PhysicsWorld::new();
        let g = scene.gravity;
        world.gravity = Vector::new(g[0] as f32, g[1] as f32, g[2] as f32);
        world.integration_parameters.dt = scene.dt as f32;
        if variant == "iterations-10" {
            world.integration_parameters.num_solver_iterations = EQUAL_ITERATIONS;
        }
        if scene.springs_without_contacts() {
            world.integration_parameters.num_solver_iterations = 1;
        }
        if knobs.substeps > 0 {
            world.integration_parameters.num_solver_iterations = knobs.substeps;
        }
        if knobs.iterations > 0 {
            world.integration_parameters.num_internal_pgs_iterations = knobs.iterations;
        }
        let mut handles = Vec::with_capacity(scene.bodies.len());
        for b in &scene.bodies {
            let v = |a: [f64; 3]| Vector::new(a[0] as f32, a[1] as f32, a[2] as f32);
            let q = b.orientation;
            let rotation = Rotation::from_xyzw(q[1] as f32, q[2] as f32, q[3] as f32, q[0] as f32)
                .normalize();
            let pose = Pose::from_parts(v(b.position), rotation);
            let builder = if b.mass > 0.0 {
                let i = b.principal_inertia();
                RigidBodyBuilder::dynamic()
                    .linvel(v(b.linear_velocity))
                    .angvel(v(b.angular_velocity))
                    .additional_mass_properties(MassProperties::new(
                        Vector::ZERO, b.mass as f32, v(i)))
            } else {
                RigidBodyBuilder::fixed()
            };
            let handle = world.bodies.insert(builder.pose(pose).can_sleep(false));
            let collider = match b.shape {
                Shape::Box { half_extents: h } => {
                    ColliderBuilder::cuboid(h[0] as f32, h[1] as f32, h[2] as f32)
                }
                Shape::Sphere { radius } => ColliderBuilder::ball(radius as f32),
                Shape::Plane => ColliderBuilder::halfspace(Unit::new_unchecked(Vector::Y)),
            };
            let collider = collider
                .density(0.0)
                .friction(b.friction as f32)
                .friction_combine_rule(CoefficientCombineRule::GeometricMean)
                .restitution(b.restitution as f32)
                .restitution_combine_rule(CoefficientCombineRule::Max)
                // a scene without collisions runs no collision detection: no pair ever forms
                .collision_groups(if scene.collisions {
                    InteractionGroups::all()
                } else {
                    InteractionGroups::none()
                });
            world.colliders.insert_with_parent(collider, handle, &mut world.bodies);
            // Rapier computes a body's mass properties in its first step; until then its inverse
            // mass is zero and an impulse at step 0 (before the first step) would do nothing
            let colliders = &world.colliders;
            world.bodies[handle].recompute_mass_properties_from_colliders(colliders);
            handles.push(handle);
        }
        Ok(Box::new(RapierWorld { world, handles, counts_contacts: scene.has_contacts() }))
    }
}

struct RapierWorld {
    world: PhysicsWorld,
    handles: Vec<RigidBodyHandle>,
    counts_contacts: bool,
}

fn v32(a: [f64; 3]) -> Vector {
    Vector::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

impl World for RapierWorld {
    fn step(&mut self) {
        self.world.step();
        // forces added for a step hold for that step only
        for &h in &self.handles {
            self.world.bodies[h].reset_forces(false);
        }
    }
    /// the solver contacts of every manifold the narrow phase kept (the points Rapier's solver
    /// takes from its manifolds, not every manifold point)
    fn contact_points(&self) -> Option<usize> {
        if !self.counts_contacts {
            return None;
        }
        Some(self.world.contact_pairs().flat_map(|p| p.manifolds().iter())
            .map(|m| m.data.solver_contacts.len()).sum())
    }
    fn state(&self, body: usize) -> State {
        let b = &self.world.bodies[self.handles[body]];
        let p = b.translation();
        let q = b.rotation();
        let v = b.linvel();
        let w = b.angvel();
        State {
            position: [p.x as f64, p.y as f64, p.z as f64],
            orientation: [q.w as f64, q.x as f64, q.y as f64, q.z as f64],
            linear_velocity: [v.x as f64, v.y as f64, v.z as f64],
            angular_velocity: [w.x as f64, w.y as f64, w.z as f64],
        }
    }
    fn add_force_at_point(&mut self, body: usize, force: [f64; 3], point: [f64; 3]) {
        self.world.bodies[self.handles[body]].add_force_at_point(v32(force), v32(point), true);
    }
    fn apply_impulse(&mut self, body: usize, impulse: [f64; 3], point: [f64; 3]) {
        self.world.bodies[self.handles[body]].apply_impulse_at_point(v32(impulse), v32(point), true);
    }
}

fn main() {
    physbench_worker::main(&Rapier);
}

#[cfg(test)]
mod tests {
    use super::*;
    use physbench_worker::checks;

    #[test]
    fn friction_mixes_by_the_scenes_pair_rule() {
        checks::pair_friction(&Rapier, "default").unwrap();
    }
    #[test]
    fn restitution_mixes_by_the_scenes_pair_rule() {
        checks::pair_restitution(&Rapier, "default").unwrap();
    }
    #[test]
    fn the_scenes_mass_and_inertia_reach_the_engine() {
        checks::mass_and_inertia(&Rapier, "default").unwrap();
    }
    #[test]
    fn the_plane_is_the_bodys_y_zero_surface() {
        checks::rests_on_the_plane(&Rapier, "default").unwrap();
    }
    #[test]
    fn the_substeps_knob_reaches_the_solver_iterations() {
        for n in [1, 4] {
            checks::substeps_reach_the_step(&Rapier, "default", n).unwrap();
        }
    }
}
