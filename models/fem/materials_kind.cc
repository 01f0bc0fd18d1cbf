// The "material" kind: a scene's "materials" (docs/physics.md "Finite elements"), named sets of a
// material model (models/materials/) and its parameters, which triangles and
// tetrahedra refer to. It holds data only: no force of its own.
#include <cmath>

#include "models/core/element_kind.h"
#include "models/fem/fem.h"
#include "models/fem/fem_elements.h"
#include "models/materials/material.h"

namespace springlab {
namespace {

void check_material(const Reporter& r, const std::string& where, const MaterialSpec& m) {
  if (find_material_model(m.model) == nullptr) {
    r.fail(field(where, "model"), "unknown model " + json_string(m.model) +
                                      " (models: " + material_model_names() + ")");
  }
  check_positive(r, field(where, "young"), m.young);
  check_finite(r, field(where, "poisson"), m.poisson);
  if (!(m.poisson > -1.0 && m.poisson < 0.5)) {
    r.fail(field(where, "poisson"),
           "must be in (-1, 0.5) (got " + shortest_text(m.poisson) + ")");
  }
  if (m.density) check_positive(r, field(where, "density"), *m.density);
  if (m.thickness) check_positive(r, field(where, "thickness"), *m.thickness);
  check_material_stability(r, m, /*tetrahedra=*/false);
}

}  // namespace

void check_material_stability(const Reporter& r, const MaterialSpec& m, bool tetrahedra) {
  const MaterialModel* model = find_material_model(m.model);
  if (model == nullptr || !(m.poisson < model->min_poisson)) return;
  if (model->unstable_in_tetrahedra_only && !tetrahedra) return;
  r.fail(field(field("materials", m.name), "poisson"),
         "the " + std::string(model->name) + " model has no stable rest state for poisson < " +
             shortest_text(model->min_poisson) + (tetrahedra && model->unstable_in_tetrahedra_only
                                                      ? " in tetrahedra"
                                                      : "") +
             " (got " + shortest_text(m.poisson) + "): " + std::string(model->unstable_why) +
             "; use poisson in [" + shortest_text(model->min_poisson) +
             ", 0.5), or the linear or stvk model for a negative ratio");
}

namespace {

void read_materials(const Json& document, const Reporter& r, Scene& scene) {
  if (!document.contains("materials")) return;
  const Json& j = document.at("materials");
  require_object(r, "materials", j);
  if (j.size() > kMaxSceneMaterials) {
    r.fail("materials", std::to_string(j.size()) + " materials, over the cap of " +
                            std::to_string(kMaxSceneMaterials) + " per scene");
  }
  Materials& out = scene.block<Materials>();
  for (const auto& [name, value] : j.items()) {
    const std::string where = field("materials", name);
    require_object(r, where, value);
    check_keys(r, where, value, {"model", "young", "poisson", "density", "thickness"},
               {"model", "young", "poisson"});
    MaterialSpec m;
    m.name = name;
    if (!value.at("model").is_string()) {
      r.fail(field(where, "model"),
             "expected a string, got " + std::string(value.at("model").type_name()));
    }
    m.model = value.at("model").get<std::string>();
    m.young = read_number(r, field(where, "young"), value.at("young"));
    m.poisson = read_number(r, field(where, "poisson"), value.at("poisson"));
    if (value.contains("density")) {
      m.density = read_number(r, field(where, "density"), value.at("density"));
    }
    if (value.contains("thickness")) {
      m.thickness = read_number(r, field(where, "thickness"), value.at("thickness"));
    }
    check_material(r, where, m);
    out.push_back(m);
  }
}

void validate_materials(const Scene& scene, const Reporter& r) {
  for (const MaterialSpec& m : scene.get<Materials>()) {
    check_material(r, field("materials", m.name), m);
  }
}

void write_materials(const Scene& scene,
                     std::vector<std::pair<std::string, std::string>>& entries) {
  const Materials* materials = scene.find<Materials>();
  if (materials == nullptr || materials->empty()) return;
  std::string text = "{";
  for (std::size_t k = 0; k < materials->size(); ++k) {
    const MaterialSpec& m = (*materials)[k];
    text += std::string(k == 0 ? "\n    " : ",\n    ") + json_string(m.name) +
            ": {\"model\": " + json_string(m.model) + ", \"young\": " + json_number(m.young) +
            ", \"poisson\": " + json_number(m.poisson);
    if (m.density) text += ", \"density\": " + json_number(*m.density);
    if (m.thickness) text += ", \"thickness\": " + json_number(*m.thickness);
    text += "}";
  }
  entries.emplace_back("materials", text + "\n  }");
}

// The elements' random instances add their own materials.
void add_no_random(Scene&, std::mt19937&, RandomStates) {}

}  // namespace

const ElementKind& material_kind() {
  static const ElementKind kind = {
      .name = "material",
      .keys = {{.name = "materials"}},
      .read = read_materials,
      .validate = validate_materials,
      .write = write_materials,
      .add_random = add_no_random,
  };
  return kind;
}

}  // namespace springlab
