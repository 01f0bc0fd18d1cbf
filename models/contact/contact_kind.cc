// The "contact" kind: a scene's "contact" settings (docs/physics.md "Contact with planes"), how its
// planes push back: the penalty k_c/2 min(d, 0)^2 (default, stiffness 1e4 N/m) or
// the IPC log-barrier kappa b(d) (Li et al. 2020; stiffness 1e3 N/m,
// distance 0.01 m). Data only: the force is the planes' (planes.cc).
#include "models/contact/contact.h"
#include "models/core/element_kind.h"

namespace springlab {
namespace {

const char* model_name(ContactModel m) {
  return m == ContactModel::kPenalty ? "penalty" : "barrier";
}

void read_contact(const Json& document, const Reporter& r, Scene& scene) {
  if (!document.contains("contact")) return;
  const Json& j = document.at("contact");
  require_object(r, "contact", j);
  check_keys(r, "contact", j, {"model", "stiffness", "distance", "smoothing"}, {});
  Contact c;
  if (j.contains("model")) {
    const Json& m = j.at("model");
    const std::string name = m.is_string() ? m.get<std::string>() : m.dump();
    if (name == "penalty") {
      c.model = ContactModel::kPenalty;
    } else if (name == "barrier") {
      c.model = ContactModel::kBarrier;
    } else {
      r.fail("contact.model", "unknown model " + (m.is_string() ? json_string(name) : name) +
                                  " (models: penalty, barrier)");
    }
  }
  if (j.contains("stiffness")) {
    c.stiffness = read_number(r, "contact.stiffness", j.at("stiffness"));
    check_positive(r, "contact.stiffness", c.stiffness);
  }
  if (j.contains("distance")) {
    c.distance = read_number(r, "contact.distance", j.at("distance"));
    check_positive(r, "contact.distance", c.distance);
  }
  if (j.contains("smoothing")) {
    c.smoothing = read_number(r, "contact.smoothing", j.at("smoothing"));
    check_positive(r, "contact.smoothing", c.smoothing);
  }
  scene.block<Contact>() = c;
}

void validate_contact(const Scene& scene, const Reporter& r) {
  const Contact* c = scene.find<Contact>();
  if (c == nullptr) return;
  if (c->stiffness != 0.0) check_positive(r, "contact.stiffness", c->stiffness);
  if (c->distance != 0.0) check_positive(r, "contact.distance", c->distance);
  check_positive(r, "contact.smoothing", c->smoothing);
}

void write_contact(const Scene& scene, std::vector<std::pair<std::string, std::string>>& entries) {
  const Contact* c = scene.find<Contact>();
  if (c == nullptr) return;
  std::string text = std::string("{\"model\": \"") + model_name(c->model) + "\"";
  if (c->stiffness > 0.0) text += ", \"stiffness\": " + json_number(c->stiffness);
  if (c->distance > 0.0) text += ", \"distance\": " + json_number(c->distance);
  text += ", \"smoothing\": " + json_number(c->smoothing) + "}";
  entries.emplace_back("contact", text);
}

void add_random_contact(Scene& scene, std::mt19937& rng, RandomStates) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Contact c;
  c.model = u(rng) < 0.5 ? ContactModel::kPenalty : ContactModel::kBarrier;
  c.stiffness = 50.0 + 100.0 * u(rng);
  c.distance = 0.5 + 0.5 * u(rng);
  scene.block<Contact>() = c;
}

}  // namespace

const ElementKind& contact_kind() {
  static const ElementKind kind = {
      .name = "contact",
      .keys = {{.name = "contact"}},
      .read = read_contact,
      .validate = validate_contact,
      .write = write_contact,
      .add_random = add_random_contact,
  };
  return kind;
}

}  // namespace springlab
