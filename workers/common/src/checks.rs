//! Checks of a worker's own mapping, for each worker crate's `cargo test`: each builds a small
//! scene whose answer follows from the scene's rules alone (docs/scene-format.md), runs it on the
//! engine in process and returns what it measured beside what the rule says, or an error naming
//! what the engine did instead. A worker that mixes friction by another rule, loses the scene's
//! restitution, or hands the engine another mass or inertia fails them.

use crate::{Body, Engine, Knobs, Scene, Shape, State};

const G: f64 = 9.81;

fn body(name: &str, shape: Shape, mass: f64, position: [f64; 3]) -> Body {
    Body {
        name: name.into(),
        shape,
        mass,
        position,
        orientation: [1.0, 0.0, 0.0, 0.0],
        linear_velocity: [0.0; 3],
        angular_velocity: [0.0; 3],
        friction: 0.5,
        restitution: 0.0,
    }
}

fn ground(friction: f64, restitution: f64) -> Body {
    Body { friction, restitution, ..body("ground", Shape::Plane, 0.0, [0.0; 3]) }
}

fn scene(name: &str, bodies: Vec<Body>, dt: f64, duration: f64, gravity: bool) -> Scene {
    let probe_bodies = (0..bodies.len()).filter(|&i| bodies[i].mass > 0.0).collect();
    Scene {
        name: name.into(),
        gravity: if gravity { [0.0, -G, 0.0] } else { [0.0; 3] },
        dt,
        duration,
        planar: true,
        collisions: bodies.len() > 1,
        bodies,
        springs: Vec::new(),
        impulses: Vec::new(),
        has_particles: false,
        probe_bodies,
        probe_interval: dt,
    }
}

/// runs the scene at the variant's own settings, calling `each` with the step index and the
/// state of `watched` after every step
fn run(engine: &dyn Engine, variant: &str, scene: &Scene, watched: usize,
       mut each: impl FnMut(i64, &State)) -> Result<(), String> {
    if let Some(why) = engine.unsupported(scene, variant) {
        return Err(format!("{}: unsupported: {why}", scene.name));
    }
    let mut world = engine.create(scene, variant, &Knobs::default())?;
    for step in 0..scene.step_count() {
        world.step();
        each(step, &world.state(watched));
    }
    match world.error().or(world.failure()) {
        Some(e) => Err(format!("{}: {e}", scene.name)),
        None => Ok(()),
    }
}

/// A 1 m cube of friction 0.25 slides at 4 m/s along a plane of friction 1: the scene's pair
/// friction is √(0.25 × 1) = 0.5, so after 0.5 s it moves at 4 − 0.5 g × 0.5 = 1.55 m/s
/// (min would leave 2.77, the mean 0.93, the product 2.77, max a box at rest). Returns the speed.
pub fn pair_friction(engine: &dyn Engine, variant: &str) -> Result<f64, String> {
    let mut cube = body("cube", Shape::Box { half_extents: [0.5; 3] }, 1.0, [0.0, 0.5, 0.0]);
    cube.friction = 0.25;
    cube.linear_velocity = [4.0, 0.0, 0.0];
    let s = scene("check-pair-friction", vec![ground(1.0, 0.0), cube], 1.0 / 60.0, 0.5, true);
    let mut speed = f64::NAN;
    run(engine, variant, &s, 1, |_, st| speed = st.linear_velocity[0])?;
    let expected = 4.0 - 0.5 * G * 0.5;
    if (speed - expected).abs() > 0.1 {
        return Err(format!("after 0.5 s the cube slides at {speed:.3} m/s; the pair rule \
                            √(μa μb) = 0.5 gives {expected:.3}"));
    }
    Ok(speed)
}

/// A sphere of restitution 0.8 falls 1 m onto a plane of restitution 0: the pair's is
/// max(0.8, 0) = 0.8, so it rises to 0.8² × 1 m = 0.64 m (min would give no bounce, the mean
/// 0.16 m). Returns the first apex's height above the touching height.
pub fn pair_restitution(engine: &dyn Engine, variant: &str) -> Result<f64, String> {
    let radius = 0.25;
    let mut ball = body("ball", Shape::Sphere { radius }, 1.0, [0.0, radius + 1.0, 0.0]);
    ball.restitution = 0.8;
    ball.friction = 0.0;
    let mut plane = ground(0.0, 0.0);
    plane.friction = 0.0;
    // 1 m takes 0.45 s; the rise to 0.64 m 0.36 s more
    let s = scene("check-pair-restitution", vec![plane, ball], 1.0 / 240.0, 1.2, true);
    let (mut bounced, mut apex) = (false, f64::NEG_INFINITY);
    run(engine, variant, &s, 1, |_, st| {
        if st.linear_velocity[1] > 0.0 {
            bounced = true;
        }
        if bounced {
            apex = apex.max(st.position[1] - radius);
        }
    })?;
    if (apex - 0.64).abs() > 0.06 {
        return Err(format!("the first apex is {apex:.3} m; the pair rule max(ea, eb) = 0.8 \
                            gives 0.64 m"));
    }
    Ok(apex)
}

/// A free box (no gravity, no contacts) of mass 2 kg and half extents 0.3, 0.2, 0.1 m takes an
/// impulse J at a world point r, once about each principal axis (J = 3 N s along y at r = 0.3 x,
/// along z at 0.2 y, along x at 0.1 z; a planar engine takes the first only): its velocity
/// becomes J / m and its angular velocity I⁻¹ (r × J). One axis at a time, so no gyroscopic term
/// enters the step. A worker that gives the engine another mass or inertia (a density, a default
/// inertia) fails. Returns the largest relative error.
pub fn mass_and_inertia(engine: &dyn Engine, variant: &str) -> Result<f64, String> {
    let b = body("box", Shape::Box { half_extents: [0.3, 0.2, 0.1] }, 2.0, [0.0; 3]);
    let inertia = b.principal_inertia();
    let mut s = scene("check-mass", vec![b], 1.0 / 60.0, 1.0 / 60.0, false);
    s.planar = false;
    let planar = engine.unsupported(&s, variant).is_some();
    s.planar = planar;
    let cases: [([f64; 3], [f64; 3]); 3] = [
        ([0.0, 3.0, 0.0], [0.3, 0.0, 0.0]),
        ([0.0, 0.0, 3.0], [0.0, 0.2, 0.0]),
        ([3.0, 0.0, 0.0], [0.0, 0.0, 0.1]),
    ];
    let mut worst: f64 = 0.0;
    for &(j, r) in cases.iter().take(if planar { 1 } else { 3 }) {
        let torque = [r[1] * j[2] - r[2] * j[1], r[2] * j[0] - r[0] * j[2],
                      r[0] * j[1] - r[1] * j[0]];
        let v = [j[0] / 2.0, j[1] / 2.0, j[2] / 2.0];
        let w = [torque[0] / inertia[0], torque[1] / inertia[1], torque[2] / inertia[2]];
        let mut world = engine.create(&s, variant, &Knobs::default())?;
        world.apply_impulse(0, j, r);
        world.step();
        let st = world.state(0);
        let (v_scale, w_scale) = (1.5, w.iter().fold(0.0f64, |m, x| m.max(x.abs())));
        let mut error: f64 = 0.0;
        for k in 0..3 {
            error = error.max((st.linear_velocity[k] - v[k]).abs() / v_scale);
            error = error.max((st.angular_velocity[k] - w[k]).abs() / w_scale);
        }
        if error > 0.02 {
            return Err(format!("after the impulse {j:?} at {r:?}: v = {:?}, ω = {:?}; J/m = \
                                {v:?}, I⁻¹(r × J) = {w:?}", st.linear_velocity,
                               st.angular_velocity));
        }
        worst = worst.max(error);
    }
    Ok(worst)
}

/// A 1 m cube rests on the plane, touching it, for 2 s: the plane's surface is at the body's
/// y = 0 and faces +y (a plane at another height or facing the other way moves the cube).
/// Returns the largest distance the cube's centre moved.
pub fn rests_on_the_plane(engine: &dyn Engine, variant: &str) -> Result<f64, String> {
    let cube = body("cube", Shape::Box { half_extents: [0.5; 3] }, 1.0, [0.0, 0.5, 0.0]);
    let s = scene("check-resting", vec![ground(0.5, 0.0), cube], 1.0 / 60.0, 2.0, true);
    let mut worst: f64 = 0.0;
    run(engine, variant, &s, 1, |_, st| {
        let d = [st.position[0], st.position[1] - 0.5, st.position[2]];
        worst = worst.max((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
    })?;
    if worst > 0.01 {
        return Err(format!("a cube resting on the plane moved {worst:.4} m"));
    }
    Ok(worst)
}

/// A body falls from rest for one step of 0.1 s with the sweep's `substeps` knob at n: n
/// semi-implicit Euler substeps of dt/n drop it g dt² (n + 1) / 2n (one step: g dt²; four:
/// 0.625 g dt²), so a knob that does not reach the engine's step (or is read as something else)
/// fails. Returns the drop.
pub fn substeps_reach_the_step(engine: &dyn Engine, variant: &str, n: usize)
    -> Result<f64, String> {
    let b = body("box", Shape::Box { half_extents: [0.5; 3] }, 1.0, [0.0, 10.0, 0.0]);
    let s = scene("check-substeps", vec![b], 0.1, 0.1, true);
    let knobs = Knobs { iterations: 0, substeps: n };
    engine.tune(variant, &knobs)?;
    let mut world = engine.create(&s, variant, &knobs)?;
    world.step();
    let drop = 10.0 - world.state(0).position[1];
    let expected = G * s.dt * s.dt * (n as f64 + 1.0) / (2.0 * n as f64);
    if (drop - expected).abs() > 0.02 * expected {
        return Err(format!("with {n} substeps one step of 0.1 s dropped the body {drop:.5} m; \
                            {n} semi-implicit Euler substeps drop it {expected:.5} m"));
    }
    Ok(drop)
}
