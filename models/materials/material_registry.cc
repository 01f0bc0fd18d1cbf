// The registered material models (material.h). Adding one: its file (a
// function returning its MaterialModel, like the ones below) and one line in
// this table.

#include "models/materials/material.h"

namespace springlab {

// Each in its own file.
const MaterialModel& linear_material();              // linear.cc
const MaterialModel& corotated_material();           // corotated.cc
const MaterialModel& stvk_material();                // stvk.cc
const MaterialModel& neo_hookean_material();         // neo_hookean.cc
const MaterialModel& stable_neo_hookean_material();  // stable_neo_hookean.cc

const std::vector<const MaterialModel*>& material_models() {
  static const std::vector<const MaterialModel*> models = {
      &linear_material(),      &corotated_material(),          &stvk_material(),
      &neo_hookean_material(), &stable_neo_hookean_material(),
  };
  return models;
}

const MaterialModel* find_material_model(std::string_view name) {
  for (const MaterialModel* m : material_models()) {
    if (m->name == name) return m;
  }
  return nullptr;
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

Tangent3 dPdF3(const MaterialModel& model, const Eigen::Matrix3d& F, const Lame& m) {
  if (model.dPdF3 != nullptr) return model.dPdF3(F, m);
  return dPdF(model, Mat(F), m);
}

}  // namespace springlab
