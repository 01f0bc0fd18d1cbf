#include "experiments/io/body_output.h"

#include "models/bodies/bodies.h"

namespace springlab {
namespace {

nlohmann::ordered_json vector_json(const Eigen::Vector3d& v) {
  return nlohmann::ordered_json::array({v.x(), v.y(), v.z()});
}
nlohmann::ordered_json matrix_json(const Eigen::Matrix3d& m) {
  auto out = nlohmann::ordered_json::array();
  for (int i = 0; i < 3; ++i) out.push_back(vector_json(m.row(i).transpose()));
  return out;
}

}  // namespace

nlohmann::ordered_json bodies_json(const Model& model, const Vector& x, const Vector& v) {
  auto out = nlohmann::ordered_json::array();
  const BodyLayout layout = body_layout(model.scene(), model.particle_order());
  for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
    const BodyState s = body_state(layout.bodies[b], layout.first[b], x.data(), v.data());
    nlohmann::ordered_json j;
    j["p"] = vector_json(s.p);
    j["A"] = matrix_json(s.A);
    j["dp"] = vector_json(s.dp);
    j["dA"] = matrix_json(s.dA);
    j["mass"] = layout.bodies[b].mass.mass;
    j["J"] = vector_json(layout.bodies[b].mass.J);
    j["linear_momentum"] = vector_json(s.linear_momentum);
    j["angular_momentum"] = vector_json(s.angular_momentum);
    j["angular_momentum_about_centre"] = vector_json(s.angular_momentum_about_centre);
    j["rigidity_strain"] = (s.A.transpose() * s.A - Eigen::Matrix3d::Identity()).norm();
    out.push_back(j);
  }
  return out;
}

}  // namespace springlab
