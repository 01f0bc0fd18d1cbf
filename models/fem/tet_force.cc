// The force of tetrahedra, fixed size (docs/physics.md "Finite elements"): the same
// element force as fem_force.cc, whose plain version for every shape is the
// reference the tests compare this one with, written for 3 x 3 F and four
// nodes so that an implicit method's force + dF/dx stays cheap.
//
// With D = Dm^-1 (its rows d_1, d_2, d_3 are the g_j of nodes 1..3; node 0
// has g_0 = -(d_1 + d_2 + d_3)) and Ds = [x1 - x0, x2 - x0, x3 - x0]:
//   F = Ds D,  f_j = -W P d_j (j = 1..3),  f_0 = -(f_1 + f_2 + f_3).
// The stiffness block of nodes i, j = 1..3 is
//   K_ij = df_i/dx_j = -W A(d_i, d_j),
// A(a, b)_rs = sum_cd a_c (dP_rc/dF_sd) b_d the tangent contracted with two
// rest-shape gradients, which the material's kernel gives (tet_kernel.h),
// in closed form where the material has one, a few flops a block
// (tangent3.h) instead of the 9 x 9 dPdF and two 9 x 9 products. Node 0's
// blocks follow from g_0 = -(d_1 + d_2 + d_3):
//   K_i0 = -sum_j K_ij,  K_0j = -sum_i K_ij,  K_00 = sum_ij K_ij.
// Each pass takes the elements kLanes at a time (a Chunk, fill below), so
// that a kernel that derives, or gives its blocks, in vector lanes
// (TetKernel::derive_lanes, lanes.h) computes a chunk's in one call.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "models/fem/fem_elements.h"
#include "models/materials/kernels/kinematics.h"  // Derived3
#include "models/materials/kernels/lanes.h"
#include "models/materials/material.h"
#include "models/materials/kernels/tet_kernel.h"

namespace springlab {
namespace {

using Matrix12 = Eigen::Matrix<double, 12, 12>;

// The element's df/dx (above), block by block, from B_ij = W A(d_i,
// d_j) (entry (r, c) of the 9 x 9 matrix of blocks is B(r, c)):
// K_ij = -B_ij for nodes 1..3, and node 0's blocks are
// K_i0 = -sum_j K_ij = S_i (S_i = sum_j B_ij), K_0i = K_i0^T (K is
// symmetric) and K_00 = -sum_i K_i0 = -sum_i S_i. Gives column s of
// each block (i, j) as add(i, j, s, u, v, w). For one element (T =
// double) or kLanes (T = Lanes, lanes.h), the same sums in the same
// order.
template <typename T, typename Entry, typename Add>
SPRINGLAB_LANES_INLINE void element_matrix(const Entry& B, const Add& add) {
  T S[9][3];  // rows 3 (i - 1) ..: S_i
  for (int row = 0; row < 9; ++row) {
    for (int s = 0; s < 3; ++s) S[row][s] = B(row, s) + B(row, 3 + s) + B(row, 6 + s);
  }
  T S_sum[3][3];
  for (int r = 0; r < 3; ++r) {
    for (int s = 0; s < 3; ++s) S_sum[r][s] = S[r][s] + S[3 + r][s] + S[6 + r][s];
  }
#pragma GCC unroll 3
  for (int s = 0; s < 3; ++s) {
    add(0, 0, s, -S_sum[0][s], -S_sum[1][s], -S_sum[2][s]);
#pragma GCC unroll 3
    for (int i = 1; i < 4; ++i) {
      const int r = 3 * (i - 1);
      add(i, 0, s, S[r][s], S[r + 1][s], S[r + 2][s]);
      add(0, i, s, S[r + s][0], S[r + s][1], S[r + s][2]);
#pragma GCC unroll 3
      for (int j = 1; j < 4; ++j) {
        const int column = 3 * (j - 1) + s;
        add(i, j, s, -B(r, column), -B(r + 1, column), -B(r + 2, column));
      }
    }
  }
}

// The same for kLanes elements whose blocks are in lanes (B[k][l]: entry
// k of element l's Tangent3): their matrices in lanes first, column s of
// block (i, j) at K[3 (12 j + 3 i + s) ..][l], then added element by
// element.
using LaneMatrices = Lanes[144];
SPRINGLAB_LANES_CLONES
void element_matrices_in_lanes(const Lanes (&B)[81], LaneMatrices& K) {
  element_matrix<Lanes>(
      [&](int r, int c) -> const Lanes& { return B[r + 9 * c]; },
      [&](int i, int j, int s, const Lanes& u, const Lanes& v, const Lanes& w) {
        Lanes* to = &K[3 * (12 * j + 3 * i + s)];
        to[0] = u;
        to[1] = v;
        to[2] = w;
      });
}

class TetrahedronForce final : public ElementTerm {
 public:
  TetrahedronForce(const Scene& scene, const ParticleOrder& order, const ElementBlock& block)
      : ElementTerm(scene, order, block),
        name_(block.name),
        free_particles_(order.free_particles) {
    const Materials& materials = scene.get<Materials>();
    tets_.reserve(block.node_lists.size());
    for (std::size_t e = 0; e < block.node_lists.size(); ++e) {
      Tet t;
      std::vector<Eigen::Vector3d> X;
      for (int j = 0; j < 4; ++j) {
        const int n = block.node_lists[e][static_cast<std::size_t>(j)];
        t.nodes[static_cast<std::size_t>(j)] = order.internal_of_scene[static_cast<std::size_t>(n)];
        X.push_back(scene.particles[static_cast<std::size_t>(n)].rest_position());
      }
      const RestShape shape = rest_shape(X, 3);
      t.D = shape.G.bottomRows(3);
      t.W = shape.W;
      t.sqrt_W = std::sqrt(t.W);
      const MaterialSpec& m = materials[static_cast<std::size_t>(block.materials[e])];
      t.model = find_material_model(m.model);
      t.lame = lame(m.young, m.poisson);
      tets_.push_back(t);
    }
  }

  std::string_view name() const override { return name_; }
  void add_force(const Configuration& c, double* f) const override {
    Chunk chunk;
    for (std::size_t first = 0; first < tets_.size(); first += kLanes) {
      fill(c, first, chunk);
      // Every P of the chunk before any is added: P comes back from the
      // material through memory, and reading it at once would straddle the
      // stores that have just written it and wait for them to reach the
      // cache (a store-forwarding stall, up to 5 ns per element,
      // benchmarks/README).
      std::array<Eigen::Matrix3d, kLanes> P;
      for (std::size_t l = 0; l < chunk.size; ++l) {
        const Tet& t = tets_[first + l];
        P[l] = t.model->tet->P(chunk.F[l], *chunk.d[l], t.lame);
      }
      for (std::size_t l = 0; l < chunk.size; ++l) {
        const Tet& t = tets_[first + l];
        const Eigen::Matrix3d minus_WDt = -t.W * t.D.transpose();
        const Eigen::Matrix3d H = P[l] * minus_WDt;  // columns f_1, f_2, f_3
        node(f, t, 0) -= H.rowwise().sum();
        for (int j = 1; j < 4; ++j) node(f, t, j) += H.col(j - 1);
      }
    }
  }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    Chunk chunk;
    for (std::size_t first = 0; first < tets_.size(); first += kLanes) {
      fill(c, first, chunk);
      for (std::size_t l = 0; l < chunk.size; ++l) {
        const Tet& t = tets_[first + l];
        sum += t.W * t.model->tet->Psi(chunk.F[l], *chunk.d[l], t.lame);
      }
    }
    return sum;
  }

  void bind_jacobian(const SparseMatrix& pattern) override {
    Slots none;
    none.fill(-1);
    slots_.assign(tets_.size(), none);
    for (std::size_t e = 0; e < tets_.size(); ++e) {
      const Tet& t = tets_[e];
      for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) {
          const int a = t.nodes[static_cast<std::size_t>(i)];
          const int b = t.nodes[static_cast<std::size_t>(j)];
          if (a >= free_particles_ || b >= free_particles_) continue;
          const BlockSlot slot = find_block_slot(pattern, 3, a, b);
          for (int s = 0; s < 3; ++s) {
            slots_[e][static_cast<std::size_t>(12 * j + 3 * i + s)] =
                slot.offset[static_cast<std::size_t>(s)];
          }
        }
      }
    }
    arrange_lane_constants();  // only dF/dx reads them
  }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx == nullptr) return;
    if (kept_.empty()) kept_.resize(tets_.size());  // keep from the first dF/dx on
    Chunk chunk;
    Lanes B[81];
    LaneMatrices K;
    for (std::size_t first = 0; first < tets_.size(); first += kLanes) {
      fill(c, first, chunk);
      if (blocks_in_lanes(chunk, B)) {
        element_matrices_in_lanes(B, K);
        for (std::size_t l = 0; l < chunk.size; ++l) add_blocks(K, l, slots_[first + l], dfdx);
      } else {
        for (std::size_t l = 0; l < chunk.size; ++l)
          add_blocks(blocks(chunk, l), slots_[first + l], dfdx);
      }
    }
  }

  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    if (kept_.empty()) kept_.resize(tets_.size());
    Chunk chunk;
    for (std::size_t first = 0; first < tets_.size(); first += kLanes) {
      fill(c, first, chunk);
      for (std::size_t l = 0; l < chunk.size; ++l) {
        Matrix12 K = Matrix12::Zero();
        add_blocks(blocks(chunk, l), dense_slots(), K.data());
        make_definite(K);
        scatter(slots_[first + l], K, dfdx);
      }
    }
  }

 protected:
  std::size_t element_count() const override { return tets_.size(); }
  Shape shape(std::size_t e) const override {
    const Tet& t = tets_[e];
    Eigen::MatrixXd G(4, 3);
    G.row(0) = -t.D.colwise().sum();
    G.bottomRows(3) = t.D;
    return {.nodes = {t.nodes.begin(), t.nodes.end()}, .G = G, .W = t.W, .model = t.model,
            .lame = t.lame};
  }

 private:
  struct Tet {
    std::array<int, 4> nodes{};  // internal indices
    Eigen::Matrix3d D;           // Dm^-1: its rows are g_1, g_2, g_3
    double W = 0.0;              // the rest volume
    double sqrt_W = 0.0;         // (the blocks take the rows of sqrt(W) D)
    const MaterialModel* model = nullptr;
    Lame lame;
  };
  // Where column s of block (i, j) starts in the value array, at 12 j + 3 i + s
  // (-1: a fixed node's block, not in the pattern).
  using Slots = std::array<int, 48>;

  static Eigen::Map<Eigen::Vector3d> node(double* f, const Tet& t, int j) {
    return Eigen::Map<Eigen::Vector3d>(f + 3 * t.nodes[static_cast<std::size_t>(j)]);
  }
  static Eigen::Map<const Eigen::Vector3d> node(const Configuration& c, const Tet& t, int j) {
    return Eigen::Map<const Eigen::Vector3d>(c.x + 3 * t.nodes[static_cast<std::size_t>(j)]);
  }

  static Eigen::Matrix3d Dw(const Tet& t) { return t.sqrt_W * t.D; }

  // F = Ds Dm^-1.
  static Eigen::Matrix3d deformation(const Configuration& c, const Tet& t) {
    Eigen::Matrix3d Ds;
    const Eigen::Vector3d x0 = node(c, t, 0);
    for (int j = 1; j < 4; ++j) Ds.col(j - 1) = node(c, t, j) - x0;
    return Ds * t.D;
  }

  // Up to kLanes consecutive elements, first .. first + size - 1: their F,
  // and what each one's kernel derives from it first (TetKernel::derive;
  // scratch, unused, where it derives nothing).
  struct Chunk {
    std::size_t first = 0, size = 0;
    std::array<Eigen::Matrix3d, kLanes> F;
    std::array<Derived3*, kLanes> d{};
    std::array<Derived3, kLanes> scratch;  // when nothing is kept
    Derived3 spare;                        // the output of lanes left over
    bool one_model = false;                // every element's model is the first's
  };

  // Fills chunk with elements first, first + 1, ... What a model derives
  // from F is kept per element once dF/dx has been asked for (kept_ is then
  // sized): derived when F differs, bit for bit, from the F of the
  // element's last call, else kept from it. An implicit method asks for the
  // energy, the force and dF/dx at the state its line search accepts, and
  // derives it once per F for all three; the result is the same as
  // deriving it again. An explicit method, which never asks for dF/dx,
  // keeps nothing. Elements whose kernel derives in lanes
  // (TetKernel::derive_lanes) are derived kLanes at a time, the same
  // result bit for bit.
  void fill(const Configuration& c, std::size_t first, Chunk& chunk) const {
    chunk.first = first;
    chunk.size = std::min<std::size_t>(kLanes, tets_.size() - first);
    const TetKernel* kernel = tets_[first].model->tet;
    chunk.one_model = true;
    std::array<std::size_t, kLanes> missing{};  // lanes to derive
    std::size_t n_missing = 0;
    for (std::size_t l = 0; l < chunk.size; ++l) {
      const Tet& t = tets_[first + l];
      chunk.one_model = chunk.one_model && t.model->tet == kernel;
      chunk.F[l] = deformation(c, t);
    }
    // In a second pass: F has just been stored, and copying it at once
    // would straddle those stores and wait for them (a store-forwarding
    // stall, benchmarks/README).
    for (std::size_t l = 0; l < chunk.size; ++l) {
      const Tet& t = tets_[first + l];
      chunk.d[l] = &chunk.scratch[l];
      if (t.model->tet->derive == nullptr) continue;
      if (kept_.empty()) {
        missing[n_missing++] = l;
        continue;
      }
      Kept& k = kept_[first + l];
      chunk.d[l] = &k.d;
      if (!k.set || !same_bits(k.F, chunk.F[l])) {
        k.F = chunk.F[l];
        k.set = true;
        missing[n_missing++] = l;
      }
    }
    if (n_missing == 0) return;
    if (chunk.one_model && kernel->derive_lanes != nullptr) {
      const Eigen::Matrix3d* in[kLanes];
      Derived3* out[kLanes];
      for (std::size_t m = 0; m < static_cast<std::size_t>(kLanes); ++m) {
        in[m] = &chunk.F[missing[m < n_missing ? m : 0]];
        out[m] = m < n_missing ? chunk.d[missing[m]] : &chunk.spare;
      }
      kernel->derive_lanes(in, out);
      return;
    }
    for (std::size_t m = 0; m < n_missing; ++m) {
      const std::size_t l = missing[m];
      tets_[first + l].model->tet->derive(chunk.F[l], *chunk.d[l]);
    }
  }

  // W A(d_i, d_j) for element l of the chunk: its blocks from the rows of D
  // scaled by w = sqrt(W) (A(a, b) is bilinear). (Dw and -W D^T are
  // computed where they are used rather than stored per element: the
  // element's data is read from memory at every call, and halving it saved
  // more time than the nine products cost, benchmarks/README.)
  Tangent3 blocks(const Chunk& chunk, std::size_t l) const {
    const Tet& t = tets_[chunk.first + l];
    return t.model->tet->blocks(chunk.F[l], *chunk.d[l], Dw(t), t.lame);
  }
  // The same for every element of the chunk at once, in lanes (entry k of
  // element l's at K[k][l]), where its kernel computes them so
  // (TetKernel::blocks_lanes); false where it does not.
  // The rows of sqrt(W) D and the Lame parameters come in lanes, arranged
  // once (lane_constants_).
  bool blocks_in_lanes(const Chunk& chunk, Lanes (&K)[81]) const {
    const TetKernel* kernel = tets_[chunk.first].model->tet;
    if (!chunk.one_model || kernel->blocks_lanes == nullptr) return false;
    const Eigen::Matrix3d* F[kLanes];
    const Derived3* d[kLanes];
    for (std::size_t l = 0; l < static_cast<std::size_t>(kLanes); ++l) {
      const std::size_t e = lane_element(chunk.first, l) - chunk.first;
      F[l] = &chunk.F[e];
      d[l] = chunk.d[e];
    }
    const LaneConstants& c = lane_constants_[chunk.first / kLanes];
    kernel->blocks_lanes(F, d, c.Dw, c.mu, c.lambda, K);
    return true;
  }

  // The element in lane l of the chunk that starts at `first`: element
  // first + l, and past the last element the chunk's first again (its
  // results there are not used).
  std::size_t lane_element(std::size_t first, std::size_t l) const {
    return first + (first + l < tets_.size() ? l : 0);
  }

  // Each chunk's rows of sqrt(W) D and Lame parameters in lanes, where some
  // element's kernel gives its blocks in lanes. Unlike the element records
  // (Dw above), these keep sqrt(W) D: arranging them into lanes at every
  // call cost more than reading them (benchmarks/README).
  void arrange_lane_constants() {
    const bool any = std::any_of(tets_.begin(), tets_.end(), [](const Tet& t) {
      return t.model->tet->blocks_lanes != nullptr;
    });
    if (!any) return;
    lane_constants_.resize((tets_.size() + kLanes - 1) / kLanes);
    for (std::size_t first = 0; first < tets_.size(); first += kLanes) {
      LaneConstants& c = lane_constants_[first / kLanes];
      for (std::size_t l = 0; l < static_cast<std::size_t>(kLanes); ++l) {
        const Tet& t = tets_[lane_element(first, l)];
        const Eigen::Matrix3d rows = Dw(t);
        for (int k = 0; k < 9; ++k) c.Dw[k][l] = rows(k / 3, k % 3);
        c.mu[l] = t.lame.mu;
        c.lambda[l] = t.lame.lambda;
      }
    }
  }

  // All four nodes free (each has its diagonal block, slot 15 k): no slot is
  // -1, and the adds need no test.
  static bool all_free(const Slots& slots) {
    return slots[0] >= 0 && slots[15] >= 0 && slots[30] >= 0 && slots[45] >= 0;
  }

  // Adds one element's df/dx to the value array at `slots`.
  static void add_blocks(const Tangent3& B, const Slots& slots, double* values) {
    const auto entry = [&](int r, int c) { return B(r, c); };
    const auto add = [&](int i, int j, int s, double u, double v, double w) {
      double* to = values + slots[static_cast<std::size_t>(12 * j + 3 * i + s)];
      to[0] += u;
      to[1] += v;
      to[2] += w;
    };
    if (all_free(slots)) {
      element_matrix<double>(entry, add);
    } else {
      element_matrix<double>(entry, [&](int i, int j, int s, double u, double v, double w) {
        if (slots[static_cast<std::size_t>(12 * j + 3 * i + s)] >= 0) add(i, j, s, u, v, w);
      });
    }
  }

  // The same for element l of a chunk whose matrices are in lanes
  // (element_matrices_in_lanes: the sums of node 0's blocks done for eight
  // elements at once, and the signs in place, so that only the adds are left
  // here).
  static void add_blocks(const LaneMatrices& K, std::size_t l, const Slots& slots,
                         double* values) {
    const auto add = [&](std::size_t t) {
      double* to = values + slots[t];
      to[0] += K[3 * t][l];
      to[1] += K[3 * t + 1][l];
      to[2] += K[3 * t + 2][l];
    };
    if (all_free(slots)) {
#pragma GCC unroll 48
      for (std::size_t t = 0; t < 48; ++t) add(t);
    } else {
      for (std::size_t t = 0; t < 48; ++t) {
        if (slots[t] >= 0) add(t);
      }
    }
  }

  // a == b bit for bit, entry by entry. F has just been stored, and
  // memcmp's wide loads straddle those stores and wait for them to reach
  // the cache (a store-forwarding stall): 9 % of neo-Hookean's force +
  // dF/dx in perf (benchmarks/README).
  // std::bit_cast<std::uint64_t>(x), which the web build's libc++ lacks:
  // the same single 8-byte load.
  static std::uint64_t bits_of(double x) {
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    return bits;
  }
  static bool same_bits(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    bool same = true;
    for (int k = 0; k < 9; ++k) {
      same = same && bits_of(a.data()[k]) == bits_of(b.data()[k]);
    }
    return same;
  }

  // The slots of a dense 12 x 12 column-major matrix (the definite part
  // works on the element's whole matrix).
  static const Slots& dense_slots() {
    static const Slots slots = [] {
      Slots d;
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
          for (int s = 0; s < 3; ++s) {
            d[static_cast<std::size_t>(12 * j + 3 * i + s)] = 12 * (3 * j + s) + 3 * i;
          }
      return d;
    }();
    return slots;
  }

  static void scatter(const Slots& slots, const Matrix12& K, double* values) {
    for (int col = 0; col < 12; ++col) {
      for (int i = 0; i < 4; ++i) {
        const int offset = slots[static_cast<std::size_t>(12 * (col / 3) + 3 * i + col % 3)];
        if (offset < 0) continue;
        Eigen::Map<Eigen::Vector3d>(values + offset) += K.col(col).segment<3>(3 * i);
      }
    }
  }

  std::string_view name_;
  int free_particles_;
  std::vector<Tet> tets_;
  std::vector<Slots> slots_;
  struct LaneConstants {
    Lanes Dw[9];  // sqrt(W) D, row-major
    Lanes mu, lambda;
  };
  std::vector<LaneConstants> lane_constants_;  // per chunk (arrange_lane_constants)
  struct Kept {
    Eigen::Matrix3d F;
    Derived3 d;
    bool set = false;
  };
  mutable std::vector<Kept> kept_;  // per element, from the first dF/dx
};

}  // namespace

std::unique_ptr<ForceTerm> make_tetrahedron_element_force(const Scene& scene,
                                                          const ParticleOrder& order,
                                                          const ElementBlock& block) {
  return std::make_unique<TetrahedronForce>(scene, order, block);
}

}  // namespace springlab
