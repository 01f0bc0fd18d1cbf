// Hooke springs (docs/physics.md "The physics"), the course's F^int:
//   d = x_i - x_j, l = |d|, u = d / l
//   F_i = -k (l - L) u,  F_j = -F_i,  V = k (l - L)^2 / 2
// Stiffness block (dF_i/dx_i = -K, dF_i/dx_j = +K):
//   K = k [ u u^T + (1 - L/l) (I - u u^T) ]
// K is indefinite when the spring is compressed (l < L): the transverse term
// is negative, which is why implicit methods cannot assume a definite matrix.
// A zero-rest-length spring is linear: F_i = -k d, K = k I.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "models/core/element_kind.h"
#include "models/springs/kernels/spring_scales.h"
#include "models/springs/kernels/vertex_spring_lanes.h"
#include "models/springs/spring_force.h"
#include "models/springs/springs.h"
#include "models/springs/vertex_pairs.h"
#include "models/springs/vertex_spring.h"

namespace springlab {

Eigen::Vector3d hooke_force(const Eigen::Vector3d& x_i, const Eigen::Vector3d& x_j, double k,
                            double rest, int dim) {
  Eigen::Vector3d d = Eigen::Vector3d::Zero();
  double l2 = 0.0;
  for (int r = 0; r < dim; ++r) {
    d[r] = x_i[r] - x_j[r];
    l2 += d[r] * d[r];
  }
  if (l2 == 0.0) return Eigen::Vector3d::Zero();
  const double l = std::sqrt(l2);
  const double k_stretch_over_l = k * (1.0 - rest / l);  // k (l - L) / l
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  for (int r = 0; r < dim; ++r) f[r] = -(k_stretch_over_l * d[r]);
  return f;
}

namespace {

struct SpringData {
  int a, b;  // internal particle indices
  double k, rest;
  int index;  // its place among the scene's springs (the file's order)
};

// Springs per block of the force loop: its scratch (d, l^2, scale) stays in
// L1 and the block's square roots and divisions run as one vector loop.
constexpr int kBlock = 64;

// Orders the springs for the force loop: each spring's lower-numbered end
// first, sorted by (a, b). Then the springs of one particle a are
// consecutive, so its force is summed in registers and stored once, and the
// loop sweeps x and f once from front to back instead of once per family of
// springs the scene lists (on a 128 x 128 cloth that is 6 sweeps of 400 KB
// each). Swapping a spring's ends changes nothing: d and F_a change sign.
std::vector<SpringData> sorted_for_locality(std::vector<SpringData> springs) {
  for (SpringData& s : springs) {
    if (s.b < s.a) std::swap(s.a, s.b);
  }
  std::stable_sort(springs.begin(), springs.end(), [](const SpringData& p, const SpringData& q) {
    return p.a != q.a ? p.a < q.a : p.b < q.b;
  });
  return springs;
}

class SpringForce final : public ForceTerm {
 public:
  SpringForce(std::vector<SpringData> springs, int dim, int free_particles)
      : springs_(sorted_for_locality(std::move(springs))), dim_(dim), free_(free_particles) {
    // Structure of arrays for the force loop: the stiffness/rest-length
    // stage reads k and L contiguously, which lets it run in SIMD; the ends
    // are stored as offsets a * dim into x and f.
    ends_.reserve(springs_.size());
    k_.reserve(springs_.size());
    rest_.reserve(springs_.size());
    for (const SpringData& s : springs_) {
      ends_.push_back({s.a * dim, s.b * dim});
      k_.push_back(s.k);
      rest_.push_back(s.rest);
    }
    in_scene_order_.resize(springs_.size());
    for (std::size_t j = 0; j < springs_.size(); ++j) in_scene_order_[j] = j;
    std::sort(in_scene_order_.begin(), in_scene_order_.end(), [&](std::size_t p, std::size_t q) {
      return springs_[p].index < springs_[q].index;
    });
  }

  std::string_view name() const override { return "spring"; }
  bool conservative() const override { return true; }

  // Each spring is the constraint |x_a - x_b| = L of stiffness k.
  // In the scene's order, not the force loop's: XPBD projects them one
  // after another in this order (a Gauss-Seidel pass), and sorted by
  // particle that pass diverges where the file's order does not (issue 37:
  // cloth 128 at 10 substeps x 1 iteration, t = 0.2 s).
  bool distance_constraints(std::vector<DistanceConstraint>& out) const override {
    for (const std::size_t j : in_scene_order_) {
      const SpringData& s = springs_[j];
      out.push_back({.a = s.a, .b = s.b, .stiffness = s.k, .length = s.rest});
    }
    return true;
  }

  void add_force(const Configuration& c, double* f) const override {
    if (dim_ == 2) add_force_d<2>(c, f); else add_force_d<3>(c, f);
  }

  double potential_energy(const Configuration& c) const override {
    return dim_ == 2 ? potential_energy_d<2>(c) : potential_energy_d<3>(c);
  }

  void declare_jacobian_blocks(JacobianPatternBuilder& builder) const override {
    for (const SpringData& s : springs_) declare_pair_blocks(builder, s.a, s.b, free_);
  }

  void bind_jacobian(const SparseMatrix& pattern) override {
    slots_.clear();
    slots_.reserve(springs_.size());
    for (const SpringData& s : springs_) {
      slots_.push_back(find_pair_slots(pattern, dim_, s.a, s.b, free_));
    }
  }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx == nullptr) return;
    if (dim_ == 2) add_stiffness_d<2, false>(c, dfdx); else add_stiffness_d<3, false>(c, dfdx);
  }

  // K = k u u^T + k (1 - L/l) (I - u u^T) is indefinite when the spring is
  // compressed (l < L): the transverse term is clamped at 0, which leaves
  // the positive semidefinite K = k u u^T.
  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    if (dim_ == 2) add_stiffness_d<2, true>(c, dfdx); else add_stiffness_d<3, true>(c, dfdx);
  }

  // Vertex block descent (models/vertex_blocks.h): particle p's springs,
  // in the scene's order, give F_p = -sum k (1 - L/l) d and
  // dF_p/dx_p = -sum K (K above; definite: its transverse term clamped at 0).
  bool has_vertex_blocks() const override { return true; }
  void add_vertex_blocks(const Configuration& c, const int* particles, int count, bool definite,
                         const VertexBlocks& out) const override {
    if (vertex_first_.empty()) build_vertex_springs();
    if (dim_ == 2) {
      definite ? add_vertex_blocks_d<2, true>(c, particles, count, out)
               : add_vertex_blocks_d<2, false>(c, particles, count, out);
    } else if (definite) {
      add_vertex_blocks_d<3, true>(c, particles, count, out);
    } else {
      // Two springs at once (kernels/vertex_spring_lanes.h).
      add_vertex_blocks_lanes3(c.x, particles, count, vertex_first_.data(),
                               vertex_springs_.data(), out);
    }
  }

 private:
  // The springs first .. first + m - 1 (j from 0): d_j = x_a - x_b and
  // l2_j = |d_j|^2.
  template <int D>
  void gather(const Configuration& c, int first, int m, double (&d)[D][kBlock],
              double* l2) const {
    const auto* ends = ends_.data() + first;
    for (int j = 0; j < m; ++j) {
      const double* xa = c.x + ends[j].a;
      const double* xb = c.x + ends[j].b;
      double sum = 0.0;
      for (int r = 0; r < D; ++r) {
        d[r][j] = xa[r] - xb[r];
        sum += d[r][j] * d[r][j];
      }
      l2[j] = sum;
    }
  }

  // The cost of a force evaluation is the square root and the division per
  // spring (the divider is the bottleneck) and the loads and stores of f,
  // so each block of springs runs in three loops: gather d = x_a - x_b, then
  // compute every scale = k (1 - L/l) of the block in one vector loop (Eigen
  // packets: several springs per sqrt/div instruction, each lane rounded
  // exactly as the scalar formula), then scatter +-scale d into f. The
  // scatter stays sequential because neighbouring springs share particles;
  // F_a is summed in registers over the run of springs that share a.
  template <int D>
  void add_force_d(const Configuration& c, double* f) const {
    alignas(64) double d[D][kBlock];
    alignas(64) double l2[kBlock];
    alignas(64) double scale[kBlock];
    const int count = static_cast<int>(ends_.size());
    for (int first = 0; first < count; first += kBlock) {
      const int m = std::min(kBlock, count - first);
      const Ends* ends = ends_.data() + first;
      gather<D>(c, first, m, d, l2);
      // F_i = -k (l - L) d / l = -k (1 - L/l) d; with L = 0 exactly -k d.
      // A spring of zero length (d = 0) gets scale 0 below, not 0 * inf.
      scale_kernel_(k_.data() + first, rest_.data() + first, l2, scale, m);
      int a = ends[0].a;
      double fa[D] = {};
      for (int j = 0; j < m; ++j) {
        if (ends[j].a != a) {
          for (int r = 0; r < D; ++r) {
            f[a + r] += fa[r];
            fa[r] = 0.0;
          }
          a = ends[j].a;
        }
        const double s = l2[j] > 0.0 ? scale[j] : 0.0;
        double* fb = f + ends[j].b;
        for (int r = 0; r < D; ++r) {
          fa[r] -= s * d[r][j];
          fb[r] += s * d[r][j];
        }
      }
      for (int r = 0; r < D; ++r) f[a + r] += fa[r];
    }
  }

  // V = sum_j k_j / 2 (l_j - L_j)^2 in the force loop's blocks: gather l^2,
  // then the square roots of a block in one vector expression (Eigen
  // packets). Implicit methods' line searches evaluate it at every trial.
  template <int D>
  double potential_energy_d(const Configuration& c) const {
    alignas(64) double l2[kBlock];
    double energy = 0.0;
    const int count = static_cast<int>(ends_.size());
    alignas(64) double d[D][kBlock];
    for (int first = 0; first < count; first += kBlock) {
      const int m = std::min(kBlock, count - first);
      gather<D>(c, first, m, d, l2);
      using Map = Eigen::Map<const Eigen::ArrayXd>;
      energy += 0.5 * (Map(k_.data() + first, m) *
                       (Map(l2, m).sqrt() - Map(rest_.data() + first, m)).square())
                          .sum();
    }
    return energy;
  }

  template <int D, bool kDefinite>
  void add_stiffness_d(const Configuration& c, double* values) const {
    for (std::size_t n = 0; n < springs_.size(); ++n) {
      const SpringData& s = springs_[n];
      double K[D][D];
      spring_stiffness<D, kDefinite>(c.x + s.a * D, c.x + s.b * D, s.k, s.rest, K);
      add_pair_blocks<D>(values, slots_[n], K, -1.0);  // dF_a/dx_a = -K
    }
  }

  template <int D, bool kDefinite>
  static void spring_stiffness(const double* xa, const double* xb, double k, double rest,
                               double (&K)[D][D]) {
    double d[D];
    double l2 = 0.0;
    for (int r = 0; r < D; ++r) {
      d[r] = xa[r] - xb[r];
      l2 += d[r] * d[r];
    }
    const double l = std::sqrt(l2);
    if (rest == 0.0 || l == 0.0) {
      // Linear spring (or a degenerate one with no direction): K = k I when
      // L = 0; a positive-rest spring at zero length has no defined K, use 0.
      const double diag = rest == 0.0 ? k : 0.0;
      for (int r = 0; r < D; ++r)
        for (int q = 0; q < D; ++q) K[r][q] = r == q ? diag : 0.0;
      return;
    }
    double transverse = k * (1.0 - rest / l);
    if (kDefinite && transverse < 0.0) transverse = 0.0;
    const double axial_minus_transverse = k - transverse;  // k L / l
    for (int r = 0; r < D; ++r) {
      for (int q = 0; q < D; ++q) {
        const double uu = d[r] * d[q] / l2;
        K[r][q] = axial_minus_transverse * uu + (r == q ? transverse : 0.0);
      }
    }
  }

  void build_vertex_springs() const {
    std::vector<std::pair<int, int>> ends;
    ends.reserve(springs_.size());
    for (const std::size_t j : in_scene_order_) ends.emplace_back(springs_[j].a, springs_[j].b);
    const VertexPairs pairs = vertex_pairs(ends, free_);
    vertex_springs_.clear();
    vertex_springs_.reserve(pairs.entries.size());
    for (const VertexPairs::Entry& e : pairs.entries) {
      const SpringData& s = springs_[in_scene_order_[static_cast<std::size_t>(e.pair)]];
      vertex_springs_.push_back({e.other * dim_, s.k, s.k * s.rest});
    }
    vertex_first_ = pairs.first;
  }

  // The plain loop (every dimension, definite or not).
  template <int D, bool kDefinite>
  void add_vertex_blocks_d(const Configuration& c, const int* particles, int count,
                           const VertexBlocks& out) const {
    const VertexSpring* springs = vertex_springs_.data();
    for (int n = 0; n < count; ++n) {
      const int p = particles[n];
      double xp[D];
      for (int r = 0; r < D; ++r) xp[r] = c.x[p * D + r];
      double f[D] = {};
      double A[D][D] = {};
      double T = 0.0;
      const int end = vertex_first_[static_cast<std::size_t>(p) + 1];
      for (int e = vertex_first_[static_cast<std::size_t>(p)]; e < end; ++e) {
        add_vertex_spring<D, kDefinite>(c.x, xp, springs[e], f, A, T);
      }
      write_vertex_block<D>(f, A, T, out.f + n * D, out.dfdx + n * D * D);
    }
  }

  mutable std::vector<int> vertex_first_;  // built at the first vertex block
  mutable std::vector<VertexSpring> vertex_springs_;

  struct Ends {
    int a, b;  // offsets a * dim, b * dim of the two ends in x and f
  };

  std::vector<SpringData> springs_;
  std::vector<std::size_t> in_scene_order_;  // springs_ positions in the scene's order
  std::vector<Ends> ends_;           // force loop: the same springs as arrays
  std::vector<double> k_, rest_;
  ScaleKernel scale_kernel_ = pick_scale_kernel();
  std::vector<PairSlots> slots_;
  int dim_;
  int free_;
};

}  // namespace

// The kind's part of the model's memory (memory_estimate.h): per spring two
// copies of the scene's Spring (the caller's scene and the model's), the
// term's sorted copy and its arrays (128 bytes: 126 fitted to the chain and
// the cloth, docs/reliability.md); once the pattern is built, its four
// slots and two off-diagonal blocks.
void spring_memory(const Scene& scene, MemoryEstimate& out) {
  const std::size_t n = scene.get<Springs>().size();
  if (n == 0) return;
  const double springs = static_cast<double>(n);
  MemoryPart part;
  part.what = std::to_string(n) + " springs";
  part.bytes = springs * static_cast<double>(2 * sizeof(Spring) + sizeof(SpringData) +
                                             sizeof(std::size_t) + 2 * sizeof(int) /* Ends */ +
                                             2 * sizeof(double));
  part.pattern_blocks = part.distinct_blocks = 2.0 * springs;
  part.slot_bytes = springs * static_cast<double>(sizeof(PairSlots));
  out.parts.push_back(std::move(part));
}

std::unique_ptr<ForceTerm> make_spring_force(const Scene& scene, const ParticleOrder& order) {
  std::vector<SpringData> springs;
  const Springs& scene_springs = scene.get<Springs>();
  springs.reserve(scene_springs.size());
  for (std::size_t j = 0; j < scene_springs.size(); ++j) {
    const Spring& s = scene_springs[j];
    if (s.k == 0.0) continue;  // a pure damper: spring_damping_force.cc
    springs.push_back({order.internal_of_scene[s.i], order.internal_of_scene[s.j], s.k, s.rest,
                       static_cast<int>(j)});
  }
  if (springs.empty()) return nullptr;
  return std::make_unique<SpringForce>(std::move(springs), order.dim, order.free_particles);
}

}  // namespace springlab
