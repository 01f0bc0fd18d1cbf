// The spring force term's fast loop (blocks of springs, a SIMD kernel for
// k (1 - L/l), forces summed per particle) against hooke_force, the plain
// formula F_i = -k (l - L) u one spring at a time (models/springs/spring_force.h).
#include <gtest/gtest.h>

#include <random>

#include "models/model/model.h"
#include "models/springs/spring_force.h"
#include "models/springs/springs.h"

namespace springlab::test_spring_force {
namespace {

// 1000 springs on disjoint pairs of free particles, so each particle's force
// is one spring's and no summation order can differ: stretched, compressed,
// zero-rest-length (linear) and zero-length springs, random stiffnesses.
// Every block of the fast loop is full, so every SIMD lane is exercised.
Scene disjoint_springs(int dim, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> position(-1.0, 1.0), stiffness(1.0, 1e4),
      rest(0.0, 2.0);
  Scene s;
  s.name = "disjoint-springs";
  s.dimension = dim;
  for (int n = 0; n < 1000; ++n) {
    Eigen::Vector3d a(position(rng), position(rng), dim == 3 ? position(rng) : 0.0);
    Eigen::Vector3d b(position(rng), position(rng), dim == 3 ? position(rng) : 0.0);
    if (n % 97 == 0) b = a;  // zero length: no direction, no force
    const int i = static_cast<int>(s.particles.size());
    s.particles.push_back({a, Eigen::Vector3d::Zero(), 1.0, false});
    s.particles.push_back({b, Eigen::Vector3d::Zero(), 1.0, false});
    const double L = n % 5 == 0 ? 0.0 : rest(rng);
    // Both orders of the ends: the fast loop swaps them to sort by particle.
    if (n % 2 == 0) {
      s.block<Springs>().push_back({i, i + 1, stiffness(rng), L, 0.0});
    } else {
      s.block<Springs>().push_back({i + 1, i, stiffness(rng), L, 0.0});
    }
  }
  return s;
}

// The forces on every particle, in scene order, from the model.
Eigen::MatrixXd model_forces(const Model& model) {
  Vector f;
  model.force(0.0, model.initial_positions(), model.initial_velocities(), f);
  // No fixed particle: the unknowns are the particles in scene order, which
  // scene_positions maps back (checked by the caller on the positions).
  return model.scene_positions(f);
}

Eigen::MatrixXd reference_forces(const Scene& s) {
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(s.particles.size()),
                                            s.dimension);
  for (const Spring& spring : s.get<Springs>()) {
    const Eigen::Vector3d fi = hooke_force(s.particles[spring.i].x, s.particles[spring.j].x,
                                           spring.k, spring.rest, s.dimension);
    for (int r = 0; r < s.dimension; ++r) {
      f(spring.i, r) += fi[r];
      f(spring.j, r) -= fi[r];
    }
  }
  return f;
}

TEST(SpringForce, FastLoopEqualsHookesLawBitForBit) {
  for (int dim : {2, 3}) {
    const Scene s = disjoint_springs(dim, 17u + static_cast<unsigned>(dim));
    const Model model(s);
    const Eigen::MatrixXd x = model.scene_positions(model.initial_positions());
    for (std::size_t p = 0; p < s.particles.size(); ++p) {
      for (int r = 0; r < dim; ++r) {
        ASSERT_EQ(x(static_cast<Eigen::Index>(p), r), s.particles[p].x[r]) << "particle order";
      }
    }
    const Eigen::MatrixXd fast = model_forces(model);
    const Eigen::MatrixXd reference = reference_forces(s);
    ASSERT_EQ(fast.rows(), reference.rows());
    int nonzero = 0;
    for (Eigen::Index p = 0; p < fast.rows(); ++p) {
      for (int r = 0; r < dim; ++r) {
        EXPECT_EQ(fast(p, r), reference(p, r)) << "dim " << dim << ", particle " << p;
        nonzero += reference(p, r) != 0.0 ? 1 : 0;
      }
    }
    EXPECT_GT(nonzero, static_cast<int>(fast.size()) * 9 / 10);
  }
}

// Where springs share particles the fast loop sums a particle's forces in
// its own order: equal up to rounding of that sum.
TEST(SpringForce, SharedParticlesAgreeToRounding) {
  std::mt19937 rng(5u);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  Scene s;
  s.name = "grid";
  s.dimension = 3;
  const int n = 12;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      s.particles.push_back({Eigen::Vector3d(a * 0.1 + jitter(rng), jitter(rng), b * 0.1 + jitter(rng)),
                             Eigen::Vector3d::Zero(), 1.0, false});
    }
  }
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const int i = a * n + b;
      if (b + 1 < n) s.block<Springs>().push_back({i, i + 1, 1000.0, 0.1, 0.0});
      if (a + 1 < n) s.block<Springs>().push_back({i + n, i, 1000.0, 0.1, 0.0});
      if (a + 1 < n && b + 1 < n) s.block<Springs>().push_back({i, i + n + 1, 1000.0, 0.1414, 0.0});
    }
  }
  const Model model(s);
  const Eigen::MatrixXd fast = model_forces(model);
  const Eigen::MatrixXd reference = reference_forces(s);
  const double scale = reference.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0.0);
  EXPECT_LE((fast - reference).cwiseAbs().maxCoeff(), 1e-13 * scale);
}

}  // namespace
}  // namespace springlab::test_spring_force
