// The force of finite elements (docs/physics.md "Finite elements"; the lecture's "generalized
// springs"): element e stores E_e = W Psi(F), F = Ds Dm^-1 = sum_j x_j g_j^T
// (fem_elements.h: the rows g_j of G), so with P = dPsi/dF
//   f_i = -dE_e/dx_i = -W P g_i,
// and the stiffness block of nodes i, j, column r (coordinate r of x_j),
//   (df_i/dx_j) e_r = -W dP[e_r g_j^T] g_i,
// with dP the material's differential (models/materials/material.h). The
// definite part for Newton is make_definite (fem_elements.h).
//
// This is the plain version, one dP per column of the stiffness, for every
// shape; tetrahedra take the fixed-size one in tet_force.cc (with the
// material's closed-form dPdF), which the tests compare with this.
#include <Eigen/Dense>
#include <cmath>
#include <string>

#include "models/fem/fem_elements.h"
#include "models/materials/material.h"

namespace springlab {
namespace {

class ElementForce final : public ElementTerm {
 public:
  ElementForce(const Scene& scene, const ParticleOrder& order, const ElementBlock& block)
      : ElementTerm(scene, order, block), name_(block.name), nodes_(block.nodes), dim_(order.dim),
        free_particles_(order.free_particles) {
    const Materials& materials = scene.get<Materials>();
    for (std::size_t e = 0; e < block.node_lists.size(); ++e) {
      Element el;
      std::vector<Eigen::Vector3d> X;
      for (int n : block.node_lists[e]) {
        el.nodes.push_back(order.internal_of_scene[static_cast<std::size_t>(n)]);
        X.push_back(scene.particles[static_cast<std::size_t>(n)].rest_position());
      }
      const MaterialSpec& m = materials[static_cast<std::size_t>(block.materials[e])];
      const RestShape shape = rest_shape(X, scene.dimension);
      el.G = shape.G;
      el.W = shape.W * (nodes_ == 3 ? m.thickness_or_one() : 1.0);
      el.model = find_material_model(m.model);
      el.lame = lame(m.young, m.poisson);
      elements_.push_back(std::move(el));
    }
  }

  std::string_view name() const override { return name_; }
  void add_force(const Configuration& c, double* f) const override {
    for (const Element& e : elements_) {
      const Mat P = e.model->P(deformation(c, e), e.lame);
      for (int i = 0; i < nodes_; ++i) {
        const Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1> fi =
            -e.W * (P * e.G.row(i).transpose());
        for (int r = 0; r < dim_; ++r) f[e.nodes[i] * dim_ + r] += fi(r);
      }
    }
  }

  double potential_energy(const Configuration& c) const override {
    double sum = 0.0;
    for (const Element& e : elements_) sum += e.W * e.model->Psi(deformation(c, e), e.lame);
    return sum;
  }

  void bind_jacobian(const SparseMatrix& pattern) override {
    for (Element& e : elements_) {
      e.slots.assign(static_cast<std::size_t>(nodes_ * nodes_), BlockSlot{});
      for (int i = 0; i < nodes_; ++i) {
        for (int j = 0; j < nodes_; ++j) {
          if (e.nodes[i] < free_particles_ && e.nodes[j] < free_particles_) {
            e.slots[static_cast<std::size_t>(i * nodes_ + j)] =
                find_block_slot(pattern, dim_, e.nodes[i], e.nodes[j]);
          }
        }
      }
    }
  }

  void add_jacobians(const Configuration& c, double* dfdx, double*) const override {
    if (dfdx == nullptr) return;
    for (const Element& e : elements_) {
      scatter(e, stiffness(c, e), dfdx);
    }
  }

  void add_definite_stiffness(const Configuration& c, double* dfdx) const override {
    for (const Element& e : elements_) {
      Eigen::MatrixXd K = stiffness(c, e);
      make_definite(K);
      scatter(e, K, dfdx);
    }
  }


 protected:
  std::size_t element_count() const override { return elements_.size(); }
  Shape shape(std::size_t e) const override {
    const Element& el = elements_[e];
    return {.nodes = el.nodes, .G = el.G, .W = el.W, .model = el.model, .lame = el.lame};
  }

 private:
  struct Element {
    std::vector<int> nodes;  // internal indices
    Eigen::MatrixXd G;       // nodes x k
    double W = 0.0;
    const MaterialModel* model = nullptr;
    Lame lame;
    std::vector<BlockSlot> slots;  // node pair (i, j) at i * nodes + j
  };

  // F = sum_j x_j g_j^T (dim x k).
  Mat deformation(const Configuration& c, const Element& e) const {
    const int k = static_cast<int>(e.G.cols());
    Mat F = Mat::Zero(dim_, k);
    for (int j = 0; j < nodes_; ++j) {
      const double* x = c.x + e.nodes[j] * dim_;
      for (int r = 0; r < dim_; ++r) {
        for (int s = 0; s < k; ++s) F(r, s) += x[r] * e.G(j, s);
      }
    }
    return F;
  }

  // df/dx of the element, (nodes dim) x (nodes dim), node-major.
  Eigen::MatrixXd stiffness(const Configuration& c, const Element& e) const {
    const Mat F = deformation(c, e);
    const int k = static_cast<int>(e.G.cols());
    Eigen::MatrixXd K(nodes_ * dim_, nodes_ * dim_);
    for (int j = 0; j < nodes_; ++j) {
      for (int r = 0; r < dim_; ++r) {
        Mat dF = Mat::Zero(dim_, k);
        dF.row(r) = e.G.row(j);  // e_r g_j^T
        const Mat dP = e.model->dP(F, dF, e.lame);
        for (int i = 0; i < nodes_; ++i) {
          K.block(i * dim_, j * dim_ + r, dim_, 1) = -e.W * (dP * e.G.row(i).transpose());
        }
      }
    }
    return K;
  }

  template <typename Matrix>
  void scatter(const Element& e, const Matrix& K, double* values) const {
    for (int i = 0; i < nodes_; ++i) {
      for (int j = 0; j < nodes_; ++j) {
        const BlockSlot& slot = e.slots[static_cast<std::size_t>(i * nodes_ + j)];
        if (!slot.valid()) continue;
        for (int col = 0; col < dim_; ++col) {
          double* column = values + slot.offset[col];
          for (int row = 0; row < dim_; ++row) column[row] += K(i * dim_ + row, j * dim_ + col);
        }
      }
    }
  }

  std::string_view name_;
  int nodes_;
  int dim_;
  int free_particles_;
  std::vector<Element> elements_;
};

}  // namespace

std::unique_ptr<ForceTerm> make_element_force(const Scene& scene, const ParticleOrder& order,
                                              const ElementBlock& block) {
  if (block.node_lists.empty()) return nullptr;
  if (block.nodes == 4 && order.dim == 3 && !block.reference) {
    return make_tetrahedron_element_force(scene, order, block);
  }
  return std::make_unique<ElementForce>(scene, order, block);
}

}  // namespace springlab
