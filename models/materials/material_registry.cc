// The registered material models (material.h), in the one registration
// idiom of springlab (models/core/registry.h). Adding one: its file (a
// class with SPRINGLAB_MATERIAL(Class, name) at its end, tet_kernel.h) and
// one line X(MaterialModel, name_material) in this table.

#include "models/materials/material.h"
#include "models/core/registry.h"
#include "models/materials/kernels/tangent3.h"

namespace springlab {

#define SPRINGLAB_MATERIALS(X)                    \
  X(MaterialModel, linear_material)               \
  X(MaterialModel, corotated_material)            \
  X(MaterialModel, stvk_material)                 \
  X(MaterialModel, neo_hookean_material)          \
  X(MaterialModel, stable_neo_hookean_material)

// NAME_material(), each in NAME.cc (SPRINGLAB_MATERIAL, tet_kernel.h).
SPRINGLAB_REGISTRY(MaterialModel, SPRINGLAB_MATERIALS, material_registry)

std::vector<const MaterialModel*> material_models() { return material_registry().entries(); }

const MaterialModel* find_material_model(std::string_view name) {
  return material_registry().find(name);
}

std::string material_model_names() {
  std::string out;
  for (const MaterialModel* m : material_models()) {
    if (!out.empty()) out += ", ";
    out += m->name;
  }
  return out;
}

Lame lame(double young, double poisson) {
  return {.mu = young / (2.0 * (1.0 + poisson)),
          .lambda = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson))};
}

Tangent dPdF(const MaterialModel& model, const Mat& F, const Lame& m) {
  const Eigen::Index d = F.rows(), k = F.cols();
  Tangent T(d * k, d * k);
  for (Eigen::Index c = 0; c < k; ++c) {
    for (Eigen::Index r = 0; r < d; ++r) {
      Mat E = Mat::Zero(d, k);
      E(r, c) = 1.0;
      const Mat dP = model.dP(F, E, m);
      for (Eigen::Index cc = 0; cc < k; ++cc) {
        for (Eigen::Index rr = 0; rr < d; ++rr) T(rr + d * cc, r + d * c) = dP(rr, cc);
      }
    }
  }
  return T;
}

}  // namespace springlab

namespace springlab {

Tangent3 tangent_blocks(const Tangent3& T, const Eigen::Matrix3d& D) {
  // A = T B: column 3 j + s is sum_d D(j, d) T.col(s + 3 d).
  Tangent3 A;
  for (int j = 0; j < 3; ++j) {
    for (int s = 0; s < 3; ++s) {
      A.col(3 * j + s) = T.col(s) * D(j, 0) + T.col(s + 3) * D(j, 1) + T.col(s + 6) * D(j, 2);
    }
  }
  // B^T A: row 3 i + r is sum_c D(i, c) A.row(r + 3 c).
  Tangent3 K;
  for (int i = 0; i < 3; ++i) {
    for (int r = 0; r < 3; ++r) {
      K.row(3 * i + r) = D(i, 0) * A.row(r) + D(i, 1) * A.row(r + 3) + D(i, 2) * A.row(r + 6);
    }
  }
  return K;
}

}  // namespace springlab
