// Finite elements at static equilibrium (docs/physics.md "Finite elements", issue 12's "tests that
// must hold"), solved by Newton on f(x) = 0 over the unknowns that are not
// prescribed (solve_static below), on meshes written as scene files:
//   - the patch test: the boundary of a mesh with an irregular interior is
//     displaced by x = A X + b, the interior starts off that field; at
//     equilibrium the interior follows the affine field (1e-9), in 2-D
//     (triangles) and 3-D (tetrahedra), for every material model;
//   - Poisson contraction: a block stretched by 1e-4 along x, its sides
//     free, contracts laterally by -nu in 3-D and -nu / (1 - nu) in plane
//     strain (2-D), within 1 %, for every material model (all linearize to
//     linear elasticity).
// (tests/test_fem.cc checks the uniform-strain patch test without a solve,
// the masses and the cantilever.)
#include <gtest/gtest.h>

#include <Eigen/SparseLU>
#include <array>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "models/model/model.h"
#include "models/materials/material.h"
#include "models/core/scene.h"
#include "models/model/scene_file.h"

namespace springlab::test_fem_equilibrium {
namespace {

// A unit square (cube) of n^dim cells, rest position X of grid point
// (i, j[, k]) = (i, j[, k]) / n, index i + (n+1) (j + (n+1) k); squares split
// into 2 triangles, cubes into 6 tetrahedra (Kuhn split). Interior rest
// points are moved by up to `jitter` of a cell (an irregular mesh).
struct Mesh {
  int dim = 2;
  std::vector<Eigen::Vector3d> X;
  std::vector<bool> boundary;
  std::vector<std::vector<int>> elements;
};

Mesh unit_mesh(int dim, int n, double jitter) {
  Mesh m;
  m.dim = dim;
  const int depth = dim == 3 ? n : 0;
  for (int k = 0; k <= depth; ++k) {
    for (int j = 0; j <= n; ++j) {
      for (int i = 0; i <= n; ++i) {
        const bool edge = i == 0 || i == n || j == 0 || j == n || (dim == 3 && (k == 0 || k == n));
        Eigen::Vector3d X(double(i) / n, double(j) / n, dim == 3 ? double(k) / n : 0.0);
        if (!edge) {
          const double p = static_cast<double>(m.X.size());
          X.x() += jitter / n * std::sin(3.0 * p);
          X.y() += jitter / n * std::cos(5.0 * p);
          if (dim == 3) X.z() += jitter / n * std::sin(7.0 * p + 1.0);
        }
        m.X.push_back(X);
        m.boundary.push_back(edge);
      }
    }
  }
  auto at = [n](int i, int j, int k) { return i + (n + 1) * (j + (n + 1) * k); };
  for (int k = 0; k < std::max(depth, 1); ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        if (dim == 2) {
          m.elements.push_back({at(i, j, 0), at(i + 1, j, 0), at(i + 1, j + 1, 0)});
          m.elements.push_back({at(i, j, 0), at(i + 1, j + 1, 0), at(i, j + 1, 0)});
          continue;
        }
        static const std::array<std::array<int, 3>, 6> orders = {
            {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
        for (const auto& order : orders) {
          std::array<int, 3> c = {i, j, k};
          std::vector<int> tet = {at(c[0], c[1], c[2])};
          for (int axis : order) {
            ++c[axis];
            tet.push_back(at(c[0], c[1], c[2]));
          }
          m.elements.push_back(tet);
        }
      }
    }
  }
  return m;
}

std::string number(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

// The mesh as a scene file: every particle free at its rest position.
Scene mesh_scene(const Mesh& m, const std::string& model, double poisson) {
  std::string text = "{\"dimension\": " + std::to_string(m.dim) +
                     ", \"materials\": {\"m\": {\"model\": \"" + model +
                     "\", \"young\": 1000, \"poisson\": " + number(poisson) +
                     "}}, \"particles\": [";
  for (std::size_t p = 0; p < m.X.size(); ++p) {
    std::string v = "[" + number(m.X[p].x()) + ", " + number(m.X[p].y());
    if (m.dim == 3) v += ", " + number(m.X[p].z());
    v += "]";
    text += (p ? ", " : "") + std::string("{\"x\": ") + v + ", \"X\": " + v + "}";
  }
  text += "], \"springs\": [], \"";
  text += m.dim == 2 ? "triangles" : "tetrahedra";
  text += "\": [";
  for (std::size_t e = 0; e < m.elements.size(); ++e) {
    text += e ? ", {\"nodes\": [" : "{\"nodes\": [";
    for (std::size_t k = 0; k < m.elements[e].size(); ++k) {
      text += (k ? ", " : "") + std::to_string(m.elements[e][k]);
    }
    text += "], \"material\": \"m\"}";
  }
  return parse_scene(text + "]}", "mesh.json");
}

// unknown[p][r]: the model's unknown of scene particle p, coordinate r.
std::vector<std::array<Eigen::Index, 3>> unknowns(const Model& model) {
  Vector index(model.dofs());
  for (Eigen::Index k = 0; k < index.size(); ++k) index[k] = static_cast<double>(k);
  const Eigen::MatrixXd at = model.scene_positions(index);
  std::vector<std::array<Eigen::Index, 3>> out(static_cast<std::size_t>(at.rows()));
  for (Eigen::Index p = 0; p < at.rows(); ++p)
    for (Eigen::Index r = 0; r < at.cols(); ++r) out[p][r] = static_cast<Eigen::Index>(at(p, r));
  return out;
}

// Newton on f(x) = 0 over the unknowns not `prescribed` (which keep their
// value in x).
Vector solve_static(const Model& model, Vector x, const std::vector<bool>& prescribed) {
  const Vector v = Vector::Zero(x.size());
  Vector f;
  SparseMatrix dfdx, dfdv;
  for (int iteration = 0; iteration < 30; ++iteration) {
    model.force(0.0, x, v, f);
    model.jacobians(0.0, x, v, &dfdx, &dfdv);
    std::vector<Eigen::Triplet<double>> entries;
    Vector rhs(x.size());
    for (int col = 0; col < dfdx.outerSize(); ++col) {
      for (SparseMatrix::InnerIterator e(dfdx, col); e; ++e) {
        if (!prescribed[e.row()] && !prescribed[col]) entries.emplace_back(e.row(), col, -e.value());
      }
    }
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      if (prescribed[k]) entries.emplace_back(k, k, 1.0);
      rhs[k] = prescribed[k] ? 0.0 : f[k];
    }
    SparseMatrix K(x.size(), x.size());
    K.setFromTriplets(entries.begin(), entries.end());
    Eigen::SparseLU<SparseMatrix> lu(K);
    if (lu.info() != Eigen::Success) break;  // the caller's checks then fail
    const Vector dx = lu.solve(rhs);
    x += dx;
    if (dx.norm() < 1e-15 * (1.0 + x.norm())) break;
  }
  return x;
}

class EquilibriumOfEveryModel : public ::testing::TestWithParam<const MaterialModel*> {};

TEST_P(EquilibriumOfEveryModel, PatchTestAffineBoundaryGivesAffineInterior) {
  for (int dim : {2, 3}) {
    SCOPED_TRACE(std::to_string(dim) + "-D");
    const Mesh mesh = unit_mesh(dim, dim == 2 ? 4 : 3, 0.2);
    const Model model(mesh_scene(mesh, std::string(GetParam()->name), 0.3));
    const auto unknown = unknowns(model);
    Eigen::Matrix3d A;
    A << 1.02, 0.01, -0.015, -0.005, 0.99, 0.02, 0.01, 0.004, 1.012;
    const Eigen::Vector3d b(0.1, -0.2, 0.05);
    Vector x = model.initial_positions();
    std::vector<bool> prescribed(x.size(), false);
    // The interior starts off the affine field (by up to 5 % of a cell;
    // further, a neo-Hookean element could start inverted).
    for (std::size_t p = 0; p < mesh.X.size(); ++p) {
      const Eigen::Vector3d target = A * mesh.X[p] + b;
      for (int r = 0; r < dim; ++r) {
        x[unknown[p][r]] = target[r];
        if (mesh.boundary[p]) {
          prescribed[unknown[p][r]] = true;
        } else {
          x[unknown[p][r]] += 0.05 / 4 * std::cos(2.0 * static_cast<double>(p) + r);
        }
      }
    }
    const Vector solved = solve_static(model, x, prescribed);
    for (std::size_t p = 0; p < mesh.X.size(); ++p) {
      const Eigen::Vector3d expected = A * mesh.X[p] + b;
      for (int r = 0; r < dim; ++r) {
        EXPECT_NEAR(solved[unknown[p][r]], expected[r], 1e-9) << "particle " << p << ", " << r;
      }
    }
  }
}

// The lateral strain of the unit block stretched by e along x: the faces
// x = 0 and x = 1 move only along x; one corner is pinned laterally and (in
// 3-D) a second against the rotation about x.
double lateral_strain(int dim, const std::string& model_name, double nu, double e) {
  const Mesh mesh = unit_mesh(dim, 3, 0.0);
  const Model model(mesh_scene(mesh, model_name, nu));
  const auto unknown = unknowns(model);
  Vector x = model.initial_positions();
  std::vector<bool> prescribed(x.size(), false);
  for (std::size_t p = 0; p < mesh.X.size(); ++p) {
    const Eigen::Vector3d& X = mesh.X[p];
    if (X.x() == 0.0 || X.x() == 1.0) {
      x[unknown[p][0]] = X.x() * (1.0 + e);
      prescribed[unknown[p][0]] = true;
    }
    if (X.x() == 0.0 && X.y() == 0.0 && X.z() == 0.0) {
      for (int r = 1; r < dim; ++r) prescribed[unknown[p][r]] = true;
    }
    if (dim == 3 && X.x() == 0.0 && X.y() == 1.0 && X.z() == 0.0) prescribed[unknown[p][2]] = true;
  }
  const Vector solved = solve_static(model, x, prescribed);
  double low = 0.0, high = 0.0;
  int n_low = 0, n_high = 0;
  for (std::size_t p = 0; p < mesh.X.size(); ++p) {
    const double y = solved[unknown[p][1]];
    if (mesh.X[p].y() == 0.0) { low += y; ++n_low; }
    if (mesh.X[p].y() == 1.0) { high += y; ++n_high; }
  }
  return high / n_high - low / n_low - 1.0;
}

TEST_P(EquilibriumOfEveryModel, PoissonContractionOfAStretchedBlock) {
  const double e = 1e-4, nu = 0.3;
  const std::string name(GetParam()->name);
  EXPECT_NEAR(lateral_strain(3, name, nu, e) / e, -nu, 0.01 * nu);
  EXPECT_NEAR(lateral_strain(2, name, nu, e) / e, -nu / (1 - nu), 0.01 * nu / (1 - nu));
}

INSTANTIATE_TEST_SUITE_P(Registry, EquilibriumOfEveryModel, ::testing::ValuesIn(material_models()),
                         [](const auto& info) {
                           std::string name(info.param->name);
                           for (char& c : name) {
                             if (c == '-') c = '_';
                           }
                           return name;
                         });

}  // namespace
}  // namespace springlab::test_fem_equilibrium
