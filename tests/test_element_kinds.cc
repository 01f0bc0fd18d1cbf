// Shared suites over the element kind registry (models/core/element_kind.h), in
// 2-D and 3-D, on each kind's own random instances and on all kinds at once:
// a kind is covered by registering it.
//   - its random instance is a valid scene whose file reads back to the same
//     scene and the same forces (its reader, writer and checks agree);
//   - force = -grad of its potentials, the stored one being what the energy
//     report shows (central differences);
//   - dF/dx and dF/dv against central differences;
//   - the definite part of dF/dx (Newton's matrix) is negative
//     semidefinite, and equals dF/dx where that already is;
//   - a kind that gives products with its Jacobians gives the assembled
//     Jacobians times p.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <ostream>
#include <random>
#include <string>

#include "models/model/model.h"
#include "random_scenes.h"
#include "registry_suite.h"
#include "models/model/scene_file.h"
#include "models/model/element_registry.h"

namespace springlab::test_element_kinds {
namespace {

using testing::random_scene;

struct KindCase {
  const ElementKind* kind;  // nullptr: every kind at once
  int dim;
};

void PrintTo(const KindCase& c, std::ostream* os) {
  *os << (c.kind != nullptr ? std::string(c.kind->name) : "all kinds") << ", " << c.dim << "-D";
}

std::vector<const ElementKind*> kinds_of(const KindCase& c) {
  return c.kind != nullptr ? std::vector<const ElementKind*>{c.kind} : element_kinds();
}

std::vector<KindCase> all_cases() {
  std::vector<KindCase> cases;
  for (int dim : {2, 3}) {
    for (const ElementKind* kind : element_kinds()) cases.push_back({kind, dim});
    cases.push_back({nullptr, dim});
  }
  return cases;
}

std::string case_name(const ::testing::TestParamInfo<KindCase>& info) {
  std::string name = info.param.kind != nullptr ? std::string(info.param.kind->name) : "all";
  std::replace(name.begin(), name.end(), '-', '_');
  return name + "_" + std::to_string(info.param.dim) + "D";
}

class EveryKind : public ::testing::TestWithParam<KindCase> {
 protected:
  Scene scene(unsigned seed, RandomStates states = RandomStates::kAny) const {
    return random_scene(kinds_of(GetParam()), GetParam().dim, seed, states);
  }
  // The same, keeping only the kinds whose force derives from potentials
  // (all of "all" but spring damping): what the potential tests need.
  Scene potential_scene(unsigned seed, RandomStates states = RandomStates::kAny) const {
    std::vector<const ElementKind*> kinds;
    for (const ElementKind* kind : kinds_of(GetParam())) {
      if (Model(random_scene({kind}, GetParam().dim, seed)).derives_from_potentials()) {
        kinds.push_back(kind);
      }
    }
    return random_scene(kinds, GetParam().dim, seed, states);
  }
};

// Each kind on its own (not all at once); one that stores energy in a column
// of its own only in the dimensions where its random instance (seed 4, the
// test's) has elements (tetrahedra, bodies: 3-D only).
class EveryKindOnItsOwn : public EveryKind {};
bool on_its_own_with_elements(const KindCase& c) {
  if (c.kind == nullptr) return false;
  if (c.kind->energy.name.empty() || c.kind->energy.work) return true;
  const Scene s = random_scene({c.kind}, c.dim, 4);
  bool has_elements = c.kind->keys.empty();
  for (const SceneKey& key : c.kind->keys) has_elements |= key.cap == 0 || key.count(s) > 0;
  return has_elements;
}

// The cases that meet `applies`, recorded for tests/test_registry_coverage.cc.
std::vector<KindCase> cases_where(const std::string& suite, bool (*applies)(const KindCase&)) {
  std::vector<KindCase> out;
  std::vector<std::string> names;
  for (const KindCase& c : all_cases()) {
    if (!applies(c)) continue;
    out.push_back(c);
    names.push_back(case_name({c, 0}));
  }
  testing::conditional_suites()[suite] = names;
  return out;
}

// Lowest eigenvalue of the symmetric part of -m.
double lowest_stiffness(const SparseMatrix& m) {
  const Eigen::MatrixXd k = -Eigen::MatrixXd(m);
  const Eigen::MatrixXd symmetric = 0.5 * (k + k.transpose());
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(symmetric).eigenvalues()[0];
}

TEST_P(EveryKind, RandomInstanceIsAValidSceneThatReadsBack) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const Scene s = scene(seed);
    ASSERT_NO_THROW(validate_scene(s, "random")) << "seed " << seed;
    const std::string text = scene_to_json(s);
    const Scene again = parse_scene(text, "random.json");
    EXPECT_EQ(scene_to_json(again), text);
    const Model model(s), reread(again);
    Vector f, g;
    model.force(0.3, model.initial_positions(), model.initial_velocities(), f);
    reread.force(0.3, reread.initial_positions(), reread.initial_velocities(), g);
    EXPECT_EQ(f, g) << "seed " << seed;
  }
}

// F = -dV/dx - dW/dv (MechanicalSystem::derives_from_potentials), and V is
// the sum of the potential columns of the energy report. A kind whose force
// has no such form (spring damping) is never asked for one.
TEST_P(EveryKind, ForceIsMinusGradientOfItsReportedPotentials) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const Model model(potential_scene(seed));
    if (!model.derives_from_potentials()) GTEST_SKIP() << "no potential";
    const double t = 0.7;
    const Vector x = model.initial_positions();
    const Vector v = model.initial_velocities();
    const Energies e = model.energies(x, v);
    const double V = model.position_potential(t, x);
    EXPECT_NEAR(e.total() - e.kinetic(), V, 1e-12 * (1.0 + std::abs(V))) << "seed " << seed;
    Vector f;
    model.force(t, x, v, f);
    const double eps = 1e-6;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      Vector xp = x, xm = x, vp = v, vm = v;
      xp[k] += eps;
      xm[k] -= eps;
      vp[k] += eps;
      vm[k] -= eps;
      const double dV =
          (model.position_potential(t, xp) - model.position_potential(t, xm)) / (2 * eps);
      const double dW =
          (model.velocity_potential(t, vp) - model.velocity_potential(t, vm)) / (2 * eps);
      EXPECT_NEAR(f[k], -dV - dW, 1e-6 * (1.0 + std::abs(f[k])))
          << "coordinate " << k << ", seed " << seed;
    }
  }
}

TEST_P(EveryKind, JacobiansMatchCentralDifferences) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const Model model(scene(seed));
    const double t = 0.37 * seed;
    const Vector x = model.initial_positions();
    const Vector v = model.initial_velocities();
    SparseMatrix dfdx, dfdv;
    model.jacobians(t, x, v, &dfdx, &dfdv);
    const Eigen::MatrixXd Kx(dfdx), Kv(dfdv);
    const double eps = 1e-6;
    Vector fp, fm;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      Vector xp = x, xm = x;
      xp[k] += eps;
      xm[k] -= eps;
      model.force(t, xp, v, fp);
      model.force(t, xm, v, fm);
      const Vector column_x = (fp - fm) / (2 * eps);
      EXPECT_LT((Kx.col(k) - column_x).norm(), 1e-6 * (1.0 + column_x.norm()))
          << "dF/dx column " << k << ", seed " << seed;
      Vector vp = v, vm = v;
      vp[k] += eps;
      vm[k] -= eps;
      model.force(t, x, vp, fp);
      model.force(t, x, vm, fm);
      const Vector column_v = (fp - fm) / (2 * eps);
      EXPECT_LT((Kv.col(k) - column_v).norm(), 1e-6 * (1.0 + column_v.norm()))
          << "dF/dv column " << k << ", seed " << seed;
    }
  }
}

// Newton's definite matrix (used when the forces derive from potentials):
// -dF/dx's definite part is positive semidefinite at any state, dF/dv is
// unchanged, and where the exact -dF/dx is already semidefinite (the
// instances' kDefinite states) the definite part is exactly dF/dx.
TEST_P(EveryKind, DefinitePartIsSemidefiniteAndExactWhereItCanBe) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    for (RandomStates states : {RandomStates::kAny, RandomStates::kDefinite}) {
      const Model model(potential_scene(seed, states));
      if (!model.derives_from_potentials()) GTEST_SKIP() << "no potential: no definite part";
      const Vector x = model.initial_positions();
      const Vector v = model.initial_velocities();
      SparseMatrix dfdx, dfdv, definite_dfdx, definite_dfdv;
      model.jacobians(0.2, x, v, &dfdx, &dfdv);
      model.definite_jacobians(0.2, x, v, &definite_dfdx, &definite_dfdv);
      const double scale = 1.0 + Eigen::MatrixXd(dfdx).norm();
      EXPECT_GT(lowest_stiffness(definite_dfdx), -1e-12 * scale) << "seed " << seed;
      EXPECT_EQ(Eigen::MatrixXd(definite_dfdv), Eigen::MatrixXd(dfdv)) << "seed " << seed;
      if (states == RandomStates::kDefinite) {
        EXPECT_GT(lowest_stiffness(dfdx), -1e-12 * scale) << "seed " << seed;
        EXPECT_EQ(Eigen::MatrixXd(definite_dfdx), Eigen::MatrixXd(dfdx)) << "seed " << seed;
      }
    }
  }
}

// A kind that gives products with its Jacobians (ForceTerm::
// add_jacobian_products: a fluid's, whose pressure Hessian Newton then never
// assembles) gives exactly the assembled Jacobians times p, exact and
// definite, before and after the implicit methods lag what they lag.
class EveryKindWithProducts : public EveryKind {};
// A kind whose random instance has terms with Jacobians, every one of which
// gives products (once lagged, as the implicit methods lag).
bool gives_products(const KindCase& c) {
  if (c.kind == nullptr) return false;
  const Model model(random_scene({c.kind}, c.dim, 1));
  const Vector x = model.initial_positions(), v = model.initial_velocities();
  model.lag_normal_forces(&x, &v, 0.01);
  bool any = false;
  for (const auto& term : model.terms()) any |= !term->constant();
  return any && model.has_jacobian_products();
}

TEST_P(EveryKindWithProducts, JacobianProductsAreTheAssembledJacobiansTimesP) {
  int checked = 0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const Model model(scene(seed));
    const Vector x = model.initial_positions();
    const Vector v = model.initial_velocities();
    for (bool lagged : {false, true}) {
      model.lag_normal_forces(lagged ? &x : nullptr, lagged ? &v : nullptr, 0.01);
      if (!model.has_jacobian_products()) continue;
      std::mt19937 rng(seed);
      std::uniform_real_distribution<double> unit(-1.0, 1.0);
      Vector p(model.dofs());
      for (Eigen::Index i = 0; i < p.size(); ++i) p[i] = unit(rng);
      for (bool definite : {false, true}) {
        SparseMatrix dfdx, dfdv;
        if (definite) {
          model.definite_jacobians(0.2, x, v, &dfdx, &dfdv);
        } else {
          model.jacobians(0.2, x, v, &dfdx, &dfdv);
        }
        Vector dfdx_p, dfdv_p;
        model.jacobian_products(definite, 0.2, x, v, p, &dfdx_p, &dfdv_p);
        const Vector want_x = dfdx * p, want_v = dfdv * p;
        const double scale_x = 1e-12 * (1.0 + Eigen::MatrixXd(dfdx).norm() * p.norm());
        const double scale_v = 1e-12 * (1.0 + Eigen::MatrixXd(dfdv).norm() * p.norm());
        EXPECT_LE((dfdx_p - want_x).norm(), scale_x) << "seed " << seed << " definite " << definite;
        EXPECT_LE((dfdv_p - want_v).norm(), scale_v) << "seed " << seed << " definite " << definite;
        ++checked;
      }
    }
    model.lag_normal_forces(nullptr, nullptr, 0.0);
  }
  EXPECT_GT(checked, 0);
}

// A kind that stores energy shows it in its column: present in the model's
// report, and -- on its own -- holding the whole potential.
TEST_P(EveryKindOnItsOwn, StoredEnergyIsInTheKindsColumn) {
  const KindCase& c = GetParam();
  const Scene s = scene(4);
  const Model model(s);
  const Energies e = model.energies(model.initial_positions(), model.initial_velocities());
  const double potential = e.total() - e.kinetic();
  if (c.kind->energy.name.empty()) {
    // It stores none: every potential of the model (that of the kinds its
    // instance needs, like friction's planes) is in a reported column.
    const double V = model.position_potential(0.0, model.initial_positions());
    EXPECT_NEAR(potential, V, 1e-14 * std::abs(e.total()) + 1e-300);
    return;
  }
  if (c.kind->energy.work) {
    // A work column (viscous-work): reported, 0 in a state's energies (the
    // time series accumulate it), not in the total.
    const std::vector<std::string>& columns = model.energy_columns();
    ASSERT_NE(std::find(columns.begin(), columns.end(), c.kind->energy.name), columns.end());
    EXPECT_EQ(e[c.kind->energy.name], 0.0);
    const double V = model.position_potential(0.0, model.initial_positions());
    EXPECT_NEAR(potential, V, 1e-14 * std::abs(e.total()) + 1e-300);
    return;
  }
  const std::vector<std::string>& columns = model.energy_columns();
  ASSERT_NE(std::find(columns.begin(), columns.end(), c.kind->energy.name), columns.end());
  // total - kinetic rounds: equal to the column up to the last bits.
  EXPECT_NEAR(e[c.kind->energy.name], potential, 1e-14 * std::abs(e.total()) + 1e-300);
  EXPECT_NE(potential, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryKind, ::testing::ValuesIn(all_cases()), case_name);
INSTANTIATE_TEST_SUITE_P(Registry, EveryKindOnItsOwn,
                         ::testing::ValuesIn(cases_where("Registry/EveryKindOnItsOwn",
                                                         on_its_own_with_elements)),
                         case_name);
INSTANTIATE_TEST_SUITE_P(Registry, EveryKindWithProducts,
                         ::testing::ValuesIn(cases_where("Registry/EveryKindWithProducts",
                                                         gives_products)),
                         case_name);

// What the registry promises every kind file: a name, a random instance, and
// columns named alike mean alike (two kinds may share one, like triangles and
// tetrahedra share "elastic").
TEST(ElementKinds, EveryKindIsCompleteAndColumnsAgree) {
  for (const ElementKind* kind : element_kinds()) {
    SCOPED_TRACE(std::string(kind->name));
    EXPECT_FALSE(kind->name.empty());
    EXPECT_NE(kind->add_random, nullptr);
    for (const SceneKey& key : kind->keys) {
      EXPECT_EQ(key.cap > 0, key.count != nullptr) << key.name;
      EXPECT_NE(kind->read, nullptr);
      EXPECT_NE(kind->write, nullptr);
      EXPECT_NE(kind->validate, nullptr);
    }
    // Its random instance exists (in 3-D, where every kind is defined), so
    // the derivative tests above cover it.
    for (unsigned seed = 1; seed <= 4; ++seed) {
      const Scene s = testing::random_scene({kind}, 3, seed);
      for (const SceneKey& key : kind->keys) {
        if (key.cap > 0) {
          EXPECT_GT(key.count(s), 0u) << key.name << ", seed " << seed;
        }
      }
    }
    for (const ElementKind* other : element_kinds()) {
      if (other->energy.name.empty() || other->energy.name != kind->energy.name) continue;
      EXPECT_EQ(other->energy.always, kind->energy.always) << other->name;
      EXPECT_EQ(other->energy.counts_with_spring, kind->energy.counts_with_spring) << other->name;
    }
  }
}

// A kind's own unknowns (element_kind.h OwnUnknowns, issue 47 item 3) enter
// the model through the hook alone: after the free particles, each kind's
// in one run in registry order, their start and mass the hook's, counted in
// the model's size, and refused by a per-particle method with the kind's
// sentence. Every kind that declares them is checked, with every kind's
// random instance in one 3-D scene.
TEST(ElementKinds, OwnUnknownsComeThroughTheHook) {
  int kinds_with_own = 0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const Scene s = testing::random_scene(element_kinds(), 3, seed);
    const Model model(s);
    const ParticleOrder& order = model.particle_order();
    int next = order.free_particles, own = 0;
    bool refused_by_own = false;
    for (const ElementKind* kind : element_kinds()) {
      const OwnUnknowns& hook = kind->own_unknowns;
      if (hook.count == nullptr) {
        EXPECT_EQ(order.first_own(kind->name), -1) << kind->name;
        continue;
      }
      SCOPED_TRACE(std::string(kind->name) + ", seed " + std::to_string(seed));
      kinds_with_own += seed == 1 ? 1 : 0;
      ASSERT_NE(hook.initial_state, nullptr);
      ASSERT_NE(hook.add_free_mass, nullptr);
      ASSERT_NE(hook.start_points, nullptr);
      EXPECT_FALSE(hook.not_per_particle.empty());
      EXPECT_EQ(order.first_own(kind->name), next);
      const int count = hook.count(s);
      const Eigen::Index at = static_cast<Eigen::Index>(next) * 3, size = count * 3;
      Vector x0 = Vector::Zero(size), v0 = Vector::Zero(size), mass = Vector::Zero(size);
      hook.initial_state(s, x0.data(), v0.data(), mass.data());
      EXPECT_EQ(model.initial_positions().segment(at, size), x0);
      EXPECT_EQ(model.initial_velocities().segment(at, size), v0);
      EXPECT_EQ(model.mass().segment(at, size), mass);
      EXPECT_TRUE((mass.array() > 0.0).all());
      Refusal why;
      if (count > 0 && !refused_by_own) {
        EXPECT_FALSE(model.vertex_form(why));
        EXPECT_EQ(why.text, hook.not_per_particle);
        refused_by_own = true;
      }
      next += count;
      own += count;
    }
    EXPECT_EQ(order.own_particles, own);
    EXPECT_EQ(model.dofs(), static_cast<Eigen::Index>(order.free_particles + own) * 3);
  }
  EXPECT_GE(kinds_with_own, 1);  // the rigid bodies
}

}  // namespace
}  // namespace springlab::test_element_kinds
