// Every output of rtp's narrow phase, broad phase and particle update on the benchmark's inputs,
// written exactly (floats as hexadecimal), so two builds can be compared with cmp: a refactor, or
// the RTP_DISABLE_SIMD build, must write the same file as the code it replaces.
//
//   build/release/bench/dump_outputs > outputs.txt
//   build/release/bench/dump_outputs --portable-particles > outputs.txt   (SIMD-off comparisons:
//   the hand-written AVX-512 particle kernels exist only with SIMD on)
#include <rtp/broadphase.h>
#include <rtp/collision.h>
#include <rtp/particles.h>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "physbench/broadphase.h"
#include "physbench/narrowphase.h"

namespace {

using physbench::NarrowphaseRegime;
using physbench::NarrowphaseShapes;

void print_vec(std::FILE* out, const rtp::Vec3& v) {
  std::fprintf(out, " %a %a %a", v.x(), v.y(), v.z());
}

void print_manifold(std::FILE* out, bool touching, const rtp::Manifold& m) {
  std::fprintf(out, "%d %u %u", int(touching), unsigned(m.count), unsigned(m.axes_tested));
  if (m.count > 0) {
    print_vec(out, m.normal);
    std::fprintf(out, " %a", m.depth);
  }
  for (std::uint8_t i = 0; i < m.count; ++i) {
    const rtp::ContactPoint& p = m.points[i];
    print_vec(out, p.point);
    const rtp::ContactFeature& f = p.feature;
    std::fprintf(out, " %a [%u %u %u %u %u %u]", p.depth, unsigned(f.reference),
                 unsigned(f.incident), unsigned(f.reference_side), unsigned(f.incident_vertex),
                 unsigned(f.type), unsigned(f.flipped));
  }
  std::fprintf(out, "\n");
}

// every set the validation and the benchmark build, through collide(), and box pairs also as hulls
void dump_narrowphase(std::FILE* out) {
  const NarrowphaseShapes kinds[] = {NarrowphaseShapes::BoxBox, NarrowphaseShapes::HullHull,
                                     NarrowphaseShapes::SphereHull, NarrowphaseShapes::BoxHull};
  for (const NarrowphaseShapes kind : kinds)
    for (const NarrowphaseRegime regime :
         {NarrowphaseRegime::Separated, NarrowphaseRegime::Touching, NarrowphaseRegime::Deep,
          NarrowphaseRegime::NearlyParallel}) {
      if (regime == NarrowphaseRegime::NearlyParallel && kind != NarrowphaseShapes::BoxBox)
        continue;
      const physbench::NarrowphaseSet set =
          physbench::make_narrowphase_set(kind, regime, 1024, 2026);
      std::fprintf(out, "narrowphase %s\n", set.name().c_str());
      for (const physbench::NarrowphasePair& pair : set.pairs) {
        const rtp::Shape& a = set.shapes[pair.shape_a];
        const rtp::Shape& b = set.shapes[pair.shape_b];
        rtp::Manifold m;
        print_manifold(out, rtp::collide(set.hulls, a, pair.pose_a, b, pair.pose_b, m), m);
        // the reverse order: the mirrored table entries
        rtp::Manifold r;
        print_manifold(out, rtp::collide(set.hulls, b, pair.pose_b, a, pair.pose_a, r), r);
        if (kind == NarrowphaseShapes::BoxBox) {
          rtp::Manifold h;
          const rtp::Shape ha = rtp::Shape::convex(a.hull), hb = rtp::Shape::convex(b.hull);
          print_manifold(out, rtp::collide_hulls(set.hulls, ha, pair.pose_a, hb, pair.pose_b, h),
                         h);
        }
      }
    }
  std::fprintf(out, "triangles\n");
  for (const physbench::TriangleQuery& q : physbench::make_triangle_queries(4096, 2026)) {
    const rtp::TrianglePoint p = rtp::closest_point_on_triangle(q.point, q.a, q.b, q.c);
    print_vec(out, p.point);
    std::fprintf(out, " %u\n", unsigned(p.feature));
  }
}

// every rtp broad phase on the benchmark's scenes, frame by frame, pairs in the order reported
void dump_broadphase(std::FILE* out) {
  using physbench::BroadphaseMotion;
  struct Case {
    BroadphaseMotion motion;
    std::size_t count;
    bool planar;
  };
  const Case cases[] = {
      {BroadphaseMotion::Coherent, 1000, false},      {BroadphaseMotion::Coherent, 10000, false},
      {BroadphaseMotion::Reshuffled, 2000, false},    {BroadphaseMotion::Line, 10000, false},
      {BroadphaseMotion::AllOverlapping, 300, false}, {BroadphaseMotion::Coherent, 10000, true}};
  for (const rtp::BroadPhaseKind kind :
       {rtp::BroadPhaseKind::SeedSap, rtp::BroadPhaseKind::IncrementalSap,
        rtp::BroadPhaseKind::BoxPruning})
    for (const Case& c : cases) {
      if (kind != rtp::BroadPhaseKind::BoxPruning && c.motion == BroadphaseMotion::Line) continue;
      physbench::BroadphaseScene scene;
      scene.motion = c.motion;
      scene.count = c.count;
      scene.planar = c.planar;
      physbench::BroadphaseFrames frames(scene);
      const auto broad = rtp::make_broad_phase(kind);
      std::vector<rtp::ProxyId> ids;
      for (const rtp::Aabb& box : frames.boxes()) ids.push_back(broad->add(box));
      std::fprintf(out, "broadphase %s %d %zu %d\n", std::string(rtp::name_of(kind)).c_str(),
                   int(c.motion), c.count, int(c.planar));
      for (int frame = 0; frame < 12; ++frame) {
        broad->update();
        std::fprintf(out, "frame %d %zu\n", frame, broad->pairs().size());
        for (const rtp::ProxyPair& p : broad->pairs()) std::fprintf(out, "%u %u\n", p.a, p.b);
        frames.advance();
        for (std::size_t i = 0; i < ids.size(); ++i) broad->move(ids[i], frames.boxes()[i]);
      }
    }
}

// the seed's attractor mode (the particles-attractors scene) and an ageing, jittered-wind one, on
// each integrator, one and two threads
void dump_particles(std::FILE* out, rtp::ParticleKernels kernels) {
  for (const rtp::ParticleIntegrator integrator :
       {rtp::ParticleIntegrator::ExplicitEuler, rtp::ParticleIntegrator::SemiImplicitEuler,
        rtp::ParticleIntegrator::Midpoint})
    for (int threads : {1, 2})
      for (bool ageing : {false, true}) {
        rtp::ParticleSystemDef def;
        def.count = 20000;
        def.spawn_min = rtp::Vec3(-3, 2, -3);
        def.spawn_max = rtp::Vec3(3, 5, 3);
        def.velocity_min = rtp::Vec3(-1, -1, -1);
        def.velocity_max = rtp::Vec3(1, 1, 1);
        def.drag = ageing ? 0.3 : 0.1;
        def.wind = ageing ? rtp::Vec3(1.0, 0.0, 0.5) : rtp::Vec3::Zero();
        def.wind_jitter = ageing ? 0.4 : 0.0;
        def.lifetime = ageing ? 1.5 : 0.0;
        def.attractors = {
            {rtp::Vec3(-2, 3, 0), 20.0}, {rtp::Vec3(2, 3, 1), 15.0}, {rtp::Vec3(0, 4, -2), -10.0}};
        def.softening = 0.2;
        def.planes = {{rtp::Vec3::Zero(), rtp::Vec3(0.25, 1.0, 0.0).normalized()},
                      {rtp::Vec3::Zero(), rtp::Vec3(-0.25, 1.0, 0.1).normalized()},
                      {rtp::Vec3::Zero(), rtp::Vec3(0.0, 1.0, -0.25).normalized()}};
        def.restitution = 0.6;
        def.friction = 0.1;
        def.integrator = integrator;
        def.threads = threads;
        def.kernels = kernels;
        rtp::ParticleSystem particles(def);
        for (int i = 0; i < 150; ++i) particles.step(1.0 / 60.0);
        std::fprintf(out, "particles %d %d %d %s %zu\n", int(integrator), threads, int(ageing),
                     particles.kernels(), particles.recycled());
        for (std::size_t i = 0; i < particles.size(); ++i) {
          print_vec(out, particles.position(i));
          print_vec(out, particles.velocity(i));
          std::fprintf(out, " %a\n", double(particles.age(i)));
        }
      }
}

}  // namespace

int main(int argc, char** argv) {
  const bool portable = argc > 1 && std::strcmp(argv[1], "--portable-particles") == 0;
  dump_narrowphase(stdout);
  dump_broadphase(stdout);
  dump_particles(stdout, portable ? rtp::ParticleKernels::Portable : rtp::ParticleKernels::Best);
  if (!portable) dump_particles(stdout, rtp::ParticleKernels::Portable);
  return 0;
}
