// The bodies' divergence rule (verdict.h; docs/command-line.md
// "Divergence"): a scene with free bodies has diverged when
//   - a body's rigidity strain |A^T A - I|_F (the quantity `run --json`
//     reports as `rigidity_strain`, 0 for a rotation) has grown by more
//     than kStrainBound = 0.1 from its start: the rigid body is no longer
//     rigid (0.1 is a stretch of about 5 % along one axis, where the
//     rigidity's stiffness keeps a body of the default kappa = 1e6 Pa within
//     about 1e-3 under its weight and contact: box-chain at dt 0.25 s with
//     generalized-alpha ends 0.38);
//   - or, in an unforced scene, its energy (kinetic + every potential,
//     gravity's included) exceeds its start by more than E_s: the exact
//     motion cannot gain energy there, so a method that doubles the
//     scene's energy scale has made it up (tumbling-box with newmark at dt
//     0.25 s: 0.987 -> 32.1 J). Unforced: no kind of the scene feeds energy
//     in (ElementKind::feeds_energy: wind); gravity, springs, elements,
//     contact and the rigidity store what they take, damping, drag, friction
//     and viscosity only take.
#include <cmath>
#include <memory>
#include <vector>

#include "models/bodies/bodies.h"
#include "models/core/force_term.h"
#include "models/core/scene.h"
#include "models/core/verdict.h"

namespace springlab {
namespace {

constexpr double kStrainBound = 0.1;

double rigidity_strain(const double* q) {
  // q: p, then the columns a_1, a_2, a_3 of A (bodies.h).
  Eigen::Matrix3d A;
  for (int i = 0; i < 3; ++i) {
    for (int r = 0; r < 3; ++r) A(r, i) = q[3 * (i + 1) + r];
  }
  return (A.transpose() * A - Eigen::Matrix3d::Identity()).norm();
}

class BodyDivergenceRule final : public DivergenceRule {
 public:
  struct Free {
    int scene_index;    // in "bodies"
    int first;          // internal index of its p pseudo-particle
    double strain0;     // its rigidity strain at t = 0
  };

  BodyDivergenceRule(std::vector<Free> bodies, const VerdictScale& scale)
      : bodies_(std::move(bodies)), scale_(scale) {}

  void measure(const Configuration& c, double total, std::vector<Verdict>& out) const override {
    // The body furthest past (or nearest to) its bound.
    Verdict strain{.rule = VerdictRule::kBodyStrain};
    for (const Free& b : bodies_) {
      const double s = rigidity_strain(c.x + 3 * b.first);
      const double bound = b.strain0 + kStrainBound;
      if (strain.where < 0 || s - bound > strain.value - strain.bound) {
        strain = {.rule = VerdictRule::kBodyStrain, .value = s, .bound = bound,
                  .where = b.scene_index};
      }
    }
    out.push_back(strain);
    if (scale_.unforced && scale_.energy_scale > 0.0) {
      out.push_back({.rule = VerdictRule::kBodyEnergy,
                     .value = total - scale_.energy_initial,
                     .bound = scale_.energy_scale});
    }
  }

 private:
  std::vector<Free> bodies_;
  VerdictScale scale_;
};

}  // namespace

// The rule in one sentence (ElementKind::divergence_sentence; bodies.cc).
extern const char kBodyDivergenceSentence[];
const char kBodyDivergenceSentence[] =
    "bodies: a body's rigidity strain |A^T A - I|_F more than 0.1 above its start, or, in an "
    "unforced scene (no wind), the energy more than E_s above its start";

std::unique_ptr<DivergenceRule> make_body_divergence_rule(const Scene& scene,
                                                          const ParticleOrder& order,
                                                          const VerdictScale& scale) {
  const BodyLayout layout = body_layout(scene, order);
  std::vector<BodyDivergenceRule::Free> free;
  for (std::size_t b = 0; b < layout.bodies.size(); ++b) {
    if (layout.first[b] < 0) continue;
    const RigidBody& body = layout.bodies[b];
    const double strain0 = (body.A0.transpose() * body.A0 - Eigen::Matrix3d::Identity()).norm();
    free.push_back({static_cast<int>(b), layout.first[b], strain0});
  }
  if (free.empty()) return nullptr;
  return std::make_unique<BodyDivergenceRule>(std::move(free), scale);
}

}  // namespace springlab
