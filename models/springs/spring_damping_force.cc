// The "spring-damping" element kind: damping along a spring (internal
// friction), docs/physics.md "The physics". It has no scene key of its own: it reads each spring's
// "damping" (springs.h, read and checked by springs.cc).
//   d = x_i - x_j, l = |d|, u = d / l, w = v_i - v_j
//   F_i = -c (w.u) u,  F_j = -F_i            (dissipates: F_i.v_i + F_j.v_j = -c (w.u)^2)
// Jacobians, with P = I - u u^T:
//   dF_i/dv_i = -c u u^T                      (symmetric, negative semidefinite)
//   dF_i/dx_i = -(c/l) [ (w.u) P + u (P w)^T ] (NOT symmetric: models with spring
//                                               damping report jacobian_symmetric() = false)
// and dF_i/d(.)_j = -dF_i/d(.)_i, dF_j = -dF_i.
#include <cmath>
#include <random>
#include <memory>
#include <vector>

#include "models/core/element_kind.h"
#include "models/springs/springs.h"
#include "models/springs/vertex_pairs.h"

namespace springlab {
namespace {

struct DamperData {
  int a, b;
  double c;
};

class SpringDampingForce final : public ForceTerm {
 public:
  SpringDampingForce(std::vector<DamperData> dampers, int dim, int free_particles)
      : dampers_(std::move(dampers)), dim_(dim), free_(free_particles) {}

  std::string_view name() const override { return "spring-damping"; }
  bool conservative() const override { return false; }
  VelocityDependence velocity_dependence() const override { return VelocityDependence::kCoupled; }
  bool symmetric_jacobians() const override { return false; }

  void add_force(const Configuration& c, double* f) const override {
    if (dim_ == 2) add_force_d<2>(c, f); else add_force_d<3>(c, f);
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    for (const DamperData& s : dampers_) declare_pair_blocks(builder, s.a, s.b, free_);
  }

  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_.clear();
    slots_.reserve(dampers_.size());
    for (const DamperData& s : dampers_) {
      slots_.push_back(find_pair_slots(pattern, dim_, s.a, s.b, free_));
    }
  }

  void add_jacobians(const Configuration& c, double* dfdx, double* dfdv) const override {
    if (dim_ == 2) add_jacobians_d<2>(c, dfdx, dfdv); else add_jacobians_d<3>(c, dfdx, dfdv);
  }

  // Vertex block descent (models/vertex_blocks.h): particle p's dampers
  // give F_p = -c (w.u) u and the blocks above with u = (x_p - x_o) / l,
  // w = v_p - v_o (both flip with the ends, which leaves every formula as
  // it is). dF_p/dx_p is not symmetric; `definite` keeps it (vbd solves
  // with the symmetric part of its block, integrators/vbd.h).
  bool has_vertex_blocks() const override { return true; }
  void add_vertex_blocks(const Configuration& c, const int* particles, int count, bool,
                         const VertexBlocks& out) const override {
    if (vertex_.first.empty()) {
      std::vector<std::pair<int, int>> ends;
      for (const DamperData& s : dampers_) ends.emplace_back(s.a, s.b);
      vertex_ = vertex_pairs(ends, free_);
    }
    if (dim_ == 2) add_vertex_blocks_d<2>(c, particles, count, out);
    else add_vertex_blocks_d<3>(c, particles, count, out);
  }

 private:
  template <int D>
  void add_vertex_blocks_d(const Configuration& c, const int* particles, int count,
                           const VertexBlocks& out) const {
    for (int n = 0; n < count; ++n) {
      const int p = particles[n];
      double* f = out.f + n * D;
      double* dfdx = out.dfdx + n * D * D;
      double* dfdv = out.dfdv != nullptr ? out.dfdv + n * D * D : nullptr;
      const int end = vertex_.first[static_cast<std::size_t>(p) + 1];
      for (int e = vertex_.first[static_cast<std::size_t>(p)]; e < end; ++e) {
        const VertexPairs::Entry& entry = vertex_.entries[static_cast<std::size_t>(e)];
        const DamperData s{p, entry.other, dampers_[static_cast<std::size_t>(entry.pair)].c};
        double u[D], w[D], l;
        if (!geometry<D>(c, s, u, w, l)) continue;
        double wu = 0.0;
        for (int r = 0; r < D; ++r) wu += w[r] * u[r];
        double pw[D];
        for (int r = 0; r < D; ++r) pw[r] = w[r] - wu * u[r];
        for (int r = 0; r < D; ++r) {
          f[r] -= s.c * wu * u[r];
          for (int q = 0; q < D; ++q) {
            const double p_rq = (r == q ? 1.0 : 0.0) - u[r] * u[q];
            dfdx[r * D + q] -= (s.c / l) * (wu * p_rq + u[r] * pw[q]);
            if (dfdv != nullptr) dfdv[r * D + q] -= s.c * u[r] * u[q];
          }
        }
      }
    }
  }
  mutable VertexPairs vertex_;  // built at the first vertex block

  // Unit direction and relative velocity of damper s; false when degenerate.
  template <int D>
  bool geometry(const Configuration& c, const DamperData& s, double (&u)[D], double (&w)[D],
                double& l) const {
    double l2 = 0.0;
    for (int r = 0; r < D; ++r) {
      u[r] = c.x[s.a * D + r] - c.x[s.b * D + r];
      w[r] = c.v[s.a * D + r] - c.v[s.b * D + r];
      l2 += u[r] * u[r];
    }
    l = std::sqrt(l2);
    if (l == 0.0) return false;  // no direction: the damper exerts no force
    for (int r = 0; r < D; ++r) u[r] /= l;
    return true;
  }

  template <int D>
  void add_force_d(const Configuration& c, double* f) const {
    for (const DamperData& s : dampers_) {
      double u[D], w[D], l;
      if (!geometry<D>(c, s, u, w, l)) continue;
      double wu = 0.0;
      for (int r = 0; r < D; ++r) wu += w[r] * u[r];
      for (int r = 0; r < D; ++r) {
        f[s.a * D + r] -= s.c * wu * u[r];
        f[s.b * D + r] += s.c * wu * u[r];
      }
    }
  }

  template <int D>
  void add_jacobians_d(const Configuration& c, double* dfdx, double* dfdv) const {
    for (std::size_t n = 0; n < dampers_.size(); ++n) {
      const DamperData& s = dampers_[n];
      double u[D], w[D], l;
      if (!geometry<D>(c, s, u, w, l)) continue;
      double wu = 0.0;
      for (int r = 0; r < D; ++r) wu += w[r] * u[r];
      if (dfdv != nullptr) {
        double B[D][D];
        for (int r = 0; r < D; ++r)
          for (int q = 0; q < D; ++q) B[r][q] = -s.c * u[r] * u[q];
        add_pair_blocks<D>(dfdv, slots_[n], B, 1.0);
      }
      if (dfdx != nullptr) {
        double pw[D];  // P w = w - (w.u) u
        for (int r = 0; r < D; ++r) pw[r] = w[r] - wu * u[r];
        double B[D][D];
        for (int r = 0; r < D; ++r) {
          for (int q = 0; q < D; ++q) {
            const double p_rq = (r == q ? 1.0 : 0.0) - u[r] * u[q];
            B[r][q] = -(s.c / l) * (wu * p_rq + u[r] * pw[q]);
          }
        }
        add_pair_blocks<D>(dfdx, slots_[n], B, 1.0);
      }
    }
  }

  std::vector<DamperData> dampers_;
  std::vector<PairSlots> slots_;
  int dim_;
  int free_;
};

std::unique_ptr<ForceTerm> make_spring_damping_force(const Scene& scene,
                                                     const ParticleOrder& order) {
  std::vector<DamperData> dampers;
  for (const Spring& s : scene.get<Springs>()) {
    if (s.damping == 0.0) continue;
    dampers.push_back({order.internal_of_scene[s.i], order.internal_of_scene[s.j], s.damping});
  }
  if (dampers.empty()) return nullptr;
  return std::make_unique<SpringDampingForce>(std::move(dampers), order.dim,
                                              order.free_particles);
}

// Damps every spring of the scene; without springs, adds pure dampers
// (k = 0, so only this kind's force acts) between some pairs of particles.
void add_random_damping(Scene& scene, std::mt19937& rng, RandomStates) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Springs& springs = scene.block<Springs>();
  if (springs.empty()) {
    const int n = static_cast<int>(scene.particles.size());
    for (int i = 0; i < n; ++i) {
      for (int j = i + 1; j < n; ++j) {
        if ((i + j) % 2 == 0) continue;
        Spring s;
        s.i = i;
        s.j = j;
        s.rest = (scene.particles[i].x - scene.particles[j].x).norm();
        springs.push_back(s);
      }
    }
  }
  for (Spring& s : springs) s.damping = 0.1 + 0.5 * u(rng);
}

}  // namespace

const ElementKind& spring_damping_kind() {
  static const ElementKind kind = {
      .name = "spring-damping",
      .refers_to_particles = true,
      .make = make_spring_damping_force,
      .add_random = add_random_damping,
  };
  return kind;
}

}  // namespace springlab
