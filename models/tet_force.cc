// The force of tetrahedra, fixed size (README "Finite elements"): the same
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
// rest-shape gradients, which each material gives in closed form, a few
// flops a block (tangent_blocks3, material.h; tangent3.h) instead of the
// 9 x 9 dPdF and two 9 x 9 products. Node 0's blocks follow from
// g_0 = -(d_1 + d_2 + d_3):
//   K_i0 = -sum_j K_ij,  K_0j = -sum_i K_ij,  K_00 = sum_ij K_ij.
#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <bit>
#include <cstdint>
#include <string>
#include <vector>

#include "models/fem_elements.h"
#include "models/materials/kinematics.h"  // Derived3
#include "models/materials/material.h"

namespace springlab {
namespace {

using Matrix12 = Eigen::Matrix<double, 12, 12>;

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
      t.Dw = std::sqrt(t.W) * t.D;
      t.minus_WDt = -t.W * t.D.transpose();
      const MaterialSpec& m = materials[static_cast<std::size_t>(block.materials[e])];
      t.model = find_material_model(m.model);
      t.lame = lame(m.young, m.poisson);
      tets_.push_back(t);
    }
  }

  std::string_view name() const override { return name_; }
  void add_force(const Configuration& c, double* f) const override {
    const auto add = [&](const Tet& t, const Eigen::Matrix3d& P) {
      const Eigen::Matrix3d H = P * t.minus_WDt;  // columns f_1, f_2, f_3
      node(f, t, 0) -= H.rowwise().sum();
      for (int j = 1; j < 4; ++j) node(f, t, j) += H.col(j - 1);
    };
    const auto P_of = [&](std::size_t e) -> Eigen::Matrix3d {
      const Tet& t = tets_[e];
      const Eigen::Matrix3d F = deformation(c, t);
      if (kept_.empty() || t.model->derive3 == nullptr) return P3(*t.model, F, t.lame);
      return t.model->P3_derived(F, derived_of(e, F), t.lame);
    };
    // Element e + 1's P is computed before element e's force is added: P
    // comes back from the material through memory, and reading it at once
    // would straddle the stores that have just written it and wait for them
    // to reach the cache (a store-forwarding stall, up to 5 ns per element,
    // benchmarks/README). A step later they have.
    if (tets_.empty()) return;
    Eigen::Matrix3d P_next = P_of(0);
    for (std::size_t e = 0; e < tets_.size(); ++e) {
      const Eigen::Matrix3d P = P_next;
      if (e + 1 < tets_.size()) P_next = P_of(e + 1);
      add(tets_[e], P);
    }
  }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for (std::size_t e = 0; e < tets_.size(); ++e) {
      const Tet& t = tets_[e];
      const Eigen::Matrix3d F = deformation(c, t);
      if (t.model->derive3 == nullptr) {
        sum += t.W * t.model->Psi(Mat(F), t.lame);
      } else if (kept_.empty()) {  // the same arithmetic, kept or not
        Derived3 d;
        t.model->derive3(F, d);
        sum += t.W * t.model->Psi3_derived(F, d, t.lame);
      } else {
        sum += t.W * t.model->Psi3_derived(F, derived_of(e, F), t.lame);
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
  }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx == nullptr) return;
    for (std::size_t e = 0; e < tets_.size(); ++e) add_stiffness(c, e, slots_[e], dfdx);
  }

  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    for (std::size_t e = 0; e < tets_.size(); ++e) {
      Matrix12 K = Matrix12::Zero();
      add_stiffness(c, e, dense_slots(), K.data());
      make_definite(K);
      scatter(slots_[e], K, dfdx);
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
    Eigen::Matrix3d Dw;          // sqrt(W) D (add_stiffness)
    Eigen::Matrix3d minus_WDt;   // -W D^T (add_force)
    double W = 0.0;              // the rest volume
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

  // F = Ds Dm^-1.
  static Eigen::Matrix3d deformation(const Configuration& c, const Tet& t) {
    Eigen::Matrix3d Ds;
    const Eigen::Vector3d x0 = node(c, t, 0);
    for (int j = 1; j < 4; ++j) Ds.col(j - 1) = node(c, t, j) - x0;
    return Ds * t.D;
  }

  // Adds the element's df/dx (above) to the value array at `slots`, block by
  // block, without forming the 12 x 12 matrix. A(a, b) is bilinear, so the
  // rows of D scaled by w = sqrt(W) (Tet::Dw) give B_ij = W A(d_i, d_j)
  // with no 9 x 9 product: K_ij = -B_ij for nodes 1..3, and node 0's blocks
  // are K_i0 = -sum_j K_ij = S_i (S_i = sum_j B_ij), K_0i = K_i0^T (K is
  // symmetric) and K_00 = -sum_i K_i0 = -sum_i S_i.
  void add_stiffness(const Configuration& c, std::size_t e, const Slots& slots,
                     double* values) const {
    const Tet& t = tets_[e];
    const Eigen::Matrix3d F = deformation(c, t);
    const Tangent3 B = t.model->derive3 != nullptr
                           ? t.model->tangent_blocks3_derived(F, derived_of(e, F), t.Dw, t.lame)
                           : tangent_blocks3(*t.model, F, t.Dw, t.lame);
    // Rows 3 (i - 1) .. of S: S_i.
    const Eigen::Matrix<double, 9, 3> S =
        B.middleCols<3>(0) + B.middleCols<3>(3) + B.middleCols<3>(6);
    const Eigen::Matrix3d S_sum = S.middleRows<3>(0) + S.middleRows<3>(3) + S.middleRows<3>(6);
    // All four nodes free (each has its diagonal block, slot 15 k): no slot is
    // -1, and the adds below need no test.
    const bool all_free = slots[0] >= 0 && slots[15] >= 0 && slots[30] >= 0 && slots[45] >= 0;
    // Adds sign * (u, v, w), column s of a block, to block (i, j).
    const auto add = [&](int i, int j, int s, double sign, double u, double v, double w) {
      const int offset = slots[static_cast<std::size_t>(12 * j + 3 * i + s)];
      if (!all_free && offset < 0) return;
      double* to = values + offset;
      to[0] += sign * u;
      to[1] += sign * v;
      to[2] += sign * w;
    };
    const auto add_column = [&](int i, int j, int s, double sign, const double* column) {
      add(i, j, s, sign, column[0], column[1], column[2]);
    };
    for (int s = 0; s < 3; ++s) {
      add_column(0, 0, s, -1.0, S_sum.col(s).data());
      for (int i = 1; i < 4; ++i) {
        const int r = 3 * (i - 1);
        add_column(i, 0, s, 1.0, S.col(s).data() + r);
        add(0, i, s, 1.0, S(r + s, 0), S(r + s, 1), S(r + s, 2));
        for (int j = 1; j < 4; ++j) add_column(i, j, s, -1.0, B.col(3 * (j - 1) + s).data() + r);
      }
    }
  }

  // What the model derives from element e's F first (MaterialModel::derive3:
  // corotated's R and S, neo-Hookean's ln J): derived when F differs, bit
  // for bit, from the F of the element's last call, else kept from it. An
  // implicit method asks for the energy, the force and dF/dx at the state
  // its line search accepts, and derives it once per F for all three; the
  // result is the same as deriving it again. The energy and the force keep
  // it only once dF/dx has been asked for (kept_ is then sized): an
  // explicit method, which never asks, pays nothing.
  const Derived3& derived_of(std::size_t e, const Eigen::Matrix3d& F) const {
    if (kept_.empty()) kept_.resize(tets_.size());
    Kept& k = kept_[e];
    if (!k.set || !same_bits(k.F, F)) {
      tets_[e].model->derive3(F, k.d);
      k.F = F;
      k.set = true;
    }
    return k.d;
  }

  // a == b bit for bit, entry by entry. F has just been stored, and
  // memcmp's wide loads straddle those stores and wait for them to reach
  // the cache (a store-forwarding stall): 9 % of neo-Hookean's force +
  // dF/dx in perf (benchmarks/README).
  static bool same_bits(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
    bool same = true;
    for (int k = 0; k < 9; ++k) {
      same = same && std::bit_cast<std::uint64_t>(a.data()[k]) ==
                         std::bit_cast<std::uint64_t>(b.data()[k]);
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
