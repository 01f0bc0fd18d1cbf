// Fluids (models/fluid_*.cc, docs/physics.md "Fluids"): the kernel, the
// neighbour search, the forces' conservation laws and Jacobians, and the
// built-in scenes against hydrostatics, linear wave theory and Martin and
// Moyce's dam break. Small 2-D scenes: the whole suite runs in seconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>
#include <sstream>

#include "experiments/driver/simulation.h"
#include "integrators/registry/registry.h"
#include "models/scenes/builtin_scenes.h"
#include "models/model/model.h"
#include "models/fluids/fluids.h"
#include "models/fluids/neighbour_grid.h"
#include "models/fluids/sph_kernel.h"
#include "models/model/scene_file.h"
#include "scenes_for_tests.h"

namespace springlab::test_fluids {
namespace {

// ---- The kernel ----

// Composite Simpson on [a, b] with n (even) intervals.
double simpson(const std::function<double(double)>& f, double a, double b, int n) {
  const double step = (b - a) / n;
  double sum = f(a) + f(b);
  for (int k = 1; k < n; ++k) sum += (k % 2 == 1 ? 4.0 : 2.0) * f(a + k * step);
  return sum * step / 3.0;
}

TEST(FluidKernel, IntegratesToOneIn2DAnd3D) {
  for (int dim : {2, 3}) {
    for (double h : {0.013, 1.0, 7.5}) {
      const CubicSpline w(h, dim);
      // The radial integral of W over the plane (2 pi r) or space (4 pi r^2),
      // piece by piece (the spline is a polynomial on [0, h] and [h, 2h]).
      auto shell = [&](double r) {
        return w.value(r) * (dim == 2 ? 2.0 * std::numbers::pi * r : 4.0 * std::numbers::pi * r * r);
      };
      const double integral = simpson(shell, 0.0, h, 2000) + simpson(shell, h, 2.0 * h, 2000);
      EXPECT_NEAR(integral, 1.0, 1e-6) << dim << "-D, h " << h;
      // And by a Cartesian lattice sum (midpoint rule), an independent check.
      const int n = dim == 2 ? 400 : 80;
      const double cell = 4.0 * h / n;
      double sum = 0.0;
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          for (int k = 0; k < (dim == 3 ? n : 1); ++k) {
            const double x = -2.0 * h + (i + 0.5) * cell, y = -2.0 * h + (j + 0.5) * cell;
            const double z = dim == 3 ? -2.0 * h + (k + 0.5) * cell : 0.0;
            sum += w.value(std::sqrt(x * x + y * y + z * z));
          }
        }
      }
      sum *= std::pow(cell, dim);
      EXPECT_NEAR(sum, 1.0, 2e-3) << dim << "-D lattice, h " << h;
    }
  }
}

TEST(FluidKernel, DerivativesMatchCentralDifferences) {
  for (int dim : {2, 3}) {
    const double h = 0.7;
    const CubicSpline w(h, dim);
    const double eps = 1e-6;
    double worst = 0.0;
    for (double q : {0.05, 0.3, 0.77, 0.99, 1.01, 1.4, 1.93}) {
      const double r = q * h;
      const double slope = (w.value(r + eps) - w.value(r - eps)) / (2 * eps);
      const double curvature = (w.slope(r + eps) - w.slope(r - eps)) / (2 * eps);
      const double scale = w.scale / h;
      worst = std::max({worst, std::abs(w.slope(r) - slope) / scale,
                        std::abs(w.curvature(r) - curvature) / (scale / h),
                        std::abs(w.slope_over_r(r) - w.slope(r) / r) / (scale / h)});
      // The gradient in space, grad W(|x|) = W'(r) x / r, against central
      // differences of W along each axis at a point of norm r.
      Eigen::Vector3d x(0.6 * r, -0.48 * r, 0.0);
      if (dim == 3) x = Eigen::Vector3d(0.48 * r, -0.6 * r, 0.64 * r);
      x *= r / x.norm();
      for (int c = 0; c < dim; ++c) {
        Eigen::Vector3d xp = x, xm = x;
        xp[c] += eps;
        xm[c] -= eps;
        const double numeric = (w.value(xp.norm()) - w.value(xm.norm())) / (2 * eps);
        worst = std::max(worst, std::abs(w.slope_over_r(r) * x[c] - numeric) / scale);
      }
    }
    EXPECT_LT(worst, 1e-8) << dim << "-D";
    EXPECT_EQ(w.value(2.0 * h), 0.0);
    EXPECT_EQ(w.slope(2.0 * h), 0.0);
  }
}

// ---- The neighbour search ----

std::vector<std::pair<int, int>> sorted(std::vector<std::pair<int, int>> pairs) {
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

TEST(FluidNeighbours, SamePairsAsAllPairs) {
  std::mt19937 rng(7);
  for (int dim : {2, 3}) {
    for (int trial = 0; trial < 6; ++trial) {
      const int n = 50 + 150 * trial;
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      std::vector<double> x(static_cast<std::size_t>(n * dim));
      for (double& c : x) c = u(rng);
      // Clusters, points on cell boundaries, far outliers, negative cells.
      if (trial % 2 == 1) {
        for (int p = 0; p < n / 3; ++p) x[static_cast<std::size_t>(p * dim)] = 0.25 * (p % 4);
      }
      if (trial >= 3) {
        x[0] = 1e9;
        x[static_cast<std::size_t>(dim)] = -3e7;
      }
      const double radius = 0.15 + 0.05 * trial;
      NeighbourGrid grid;
      grid.build(x.data(), n, dim, radius);
      const auto expected = all_pairs_within(x.data(), n, dim, radius);
      EXPECT_EQ(sorted(grid.pairs()), expected) << dim << "-D, trial " << trial;
      EXPECT_FALSE(expected.empty());
      // Each particle's run of partners: all its pairs as first point.
      for (int i = 0; i < n; ++i) {
        for (int k = grid.first(i); k < grid.first(i + 1); ++k) {
          EXPECT_EQ(grid.pairs()[static_cast<std::size_t>(k)].first, i);
        }
      }
    }
  }
}

TEST(FluidNeighbours, APointNotFiniteHasNoPartners) {
  std::vector<double> x = {0.0, 0.0, 0.1, 0.0, NAN, 0.0, 0.05, 0.05};
  NeighbourGrid grid;
  grid.build(x.data(), 4, 2, 0.2);
  for (const auto& [i, j] : grid.pairs()) {
    EXPECT_NE(i, 2);
    EXPECT_NE(j, 2);
  }
  EXPECT_EQ(grid.pairs().size(), 3u);
}

// The particles' Verlet list (sph_particles.h): after moves below and
// above its skin, of one particle or all, the pairs are exactly those within
// the support that have a free particle (a third of the particles are fixed
// and never move), and every density the sum over all particles within the
// support, fixed pairs included.
TEST(FluidNeighbours, TheVerletListFindsEveryPairAfterEachMove) {
  std::mt19937 rng(11);
  for (int dim : {2, 3}) {
    Fluid fluid;
    fluid.spacing = 0.1;
    const int n = dim == 2 ? 200 : 300;
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<double> x(static_cast<std::size_t>(n * dim));
    for (double& c : x) c = u(rng);
    std::vector<int> index(static_cast<std::size_t>(n));
    std::vector<char> fixed(static_cast<std::size_t>(n));
    for (int a = 0; a < n; ++a) {
      index[static_cast<std::size_t>(a)] = a;
      fixed[static_cast<std::size_t>(a)] = a % 3 == 0;
    }
    SphParticles particles(fluid, index, std::vector<double>(static_cast<std::size_t>(n), 1.0),
                           dim, fixed);
    const CubicSpline& w = particles.kernel();
    const double support = w.support();
    auto as_searched = [&](const std::string& what) {
      std::vector<std::pair<int, int>> want;
      for (const auto& [a, b] : all_pairs_within(x.data(), n, dim, support)) {
        if (!fixed[static_cast<std::size_t>(a)] || !fixed[static_cast<std::size_t>(b)]) {
          want.emplace_back(a, b);
        }
      }
      EXPECT_EQ(sorted(particles.pairs()), want) << what;
      for (int a = 0; a < n; ++a) {
        double rho = 0.0;  // every particle within the support, a itself included
        for (int b = 0; b < n; ++b) {
          double r2 = 0.0;
          for (int r = 0; r < dim; ++r) {
            const double d = x[static_cast<std::size_t>(a * dim + r)] - x[static_cast<std::size_t>(b * dim + r)];
            r2 += d * d;
          }
          if (r2 < support * support) rho += w.value(std::sqrt(r2));
        }
        EXPECT_NEAR(particles.density()[static_cast<std::size_t>(a)], rho, 1e-12 * rho) << what;
      }
    };
    const double skin_move = SphParticles::kSkin * 0.5 * support;  // the list's limit
    particles.update(x.data());
    as_searched(std::to_string(dim) + "-D, first search");
    // Moves of every free particle by 0.3, 0.9 and 1.5 times the limit, then
    // one particle next to another.
    for (double factor : {0.3, 0.9, 1.5}) {
      std::normal_distribution<double> step(0.0, 1.0);
      for (int a = 0; a < n; ++a) {
        if (fixed[static_cast<std::size_t>(a)]) continue;
        double dir[3], norm = 0.0;
        for (int r = 0; r < dim; ++r) norm += (dir[r] = step(rng)) * dir[r];
        norm = std::sqrt(norm);
        for (int r = 0; r < dim; ++r) {
          x[static_cast<std::size_t>(a * dim + r)] += factor * skin_move * dir[r] / norm;
        }
      }
      particles.update(x.data());
      as_searched(std::to_string(dim) + "-D, every free particle moved by " +
                  std::to_string(factor) + " x the limit");
    }
    for (int r = 0; r < dim; ++r) {
      x[static_cast<std::size_t>(dim + r)] = x[static_cast<std::size_t>(2 * dim + r)] + 0.1 * support;
    }
    particles.update(x.data());
    as_searched(std::to_string(dim) + "-D, one particle moved next to another");
  }
  // Two particles just beyond the list's reach, (1 + kSkin) 2h, closing head
  // on by 1.5 times the limit each: within 2h now, which only a new search
  // finds (a limit twice as lax would keep the old list and miss them).
  Fluid fluid;
  fluid.spacing = 0.1;
  SphParticles two(fluid, {0, 1}, {1.0, 1.0}, 2);
  const double support = two.kernel().support();
  const double limit = SphParticles::kSkin * 0.5 * support;
  std::vector<double> x = {0.0, 0.0, 1.001 * (1.0 + SphParticles::kSkin) * support, 0.0};
  two.update(x.data());
  EXPECT_TRUE(two.pairs().empty());
  x[0] += 1.5 * limit;
  x[2] -= 1.5 * limit;
  two.update(x.data());
  ASSERT_EQ(two.pairs().size(), 1u);
  EXPECT_NEAR(two.distance(0), x[2] - x[0], 1e-15);
  // The same approach in two moves of 0.6 times the limit each: each is
  // below it, their sum is not, and the moves count from the last search
  // (a list kept while each update moves less than the limit would miss
  // the pair).
  SphParticles again(fluid, {0, 1}, {1.0, 1.0}, 2);
  x = {0.0, 0.0, 1.001 * (1.0 + SphParticles::kSkin) * support, 0.0};
  again.update(x.data());
  for (int move = 0; move < 2; ++move) {
    x[0] += 0.6 * limit;
    x[2] -= 0.6 * limit;
    again.update(x.data());
  }
  ASSERT_LT(x[2] - x[0], support);
  EXPECT_EQ(again.pairs().size(), 1u);
}

// ---- Forces ----

TEST(FluidForces, ConserveMomentumWithoutBoundaries) {
  for (int dim : {2, 3}) {
    const Model model(testing::fluid_blob(dim, 200, 3, 0.05));
    Vector f;
    model.force(0.0, model.initial_positions(), model.initial_velocities(), f);
    Eigen::Vector3d total = Eigen::Vector3d::Zero();
    double magnitude = 0.0;
    for (Eigen::Index k = 0; k < f.size(); ++k) {
      total[k % dim] += f[k];
      magnitude += std::abs(f[k]);
    }
    ASSERT_GT(magnitude, 0.0);
    EXPECT_LT(total.norm(), 1e-12 * magnitude) << dim << "-D";
    // The viscosity only dissipates.
    EXPECT_LT(model.nonconservative_power(0.0, model.initial_positions(),
                                          model.initial_velocities()), 0.0);
  }
}

// dF/dx and dF/dv of pressure + viscosity against central differences on
// blobs of a few dozen particles (every particle coupled to many), and the
// pressure's force against its energy.
TEST(FluidForces, JacobiansMatchCentralDifferences) {
  for (int dim : {2, 3}) {
    const Model model(testing::fluid_blob(dim, dim == 2 ? 40 : 30, 11, 0.05));
    const Vector x = model.initial_positions(), v = model.initial_velocities();
    SparseMatrix dfdx, dfdv;
    model.jacobians(0.0, x, v, &dfdx, &dfdv);
    const Eigen::MatrixXd Kx(dfdx), Kv(dfdv);
    const double eps = 1e-7;
    double worst_x = 0.0, worst_v = 0.0;
    Vector fp, fm;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      Vector xp = x, xm = x;
      xp[k] += eps;
      xm[k] -= eps;
      model.force(0.0, xp, v, fp);
      model.force(0.0, xm, v, fm);
      const Vector column = (fp - fm) / (2 * eps);
      worst_x = std::max(worst_x, (Kx.col(k) - column).norm() / (1.0 + column.norm()));
      // (F is affine in v: a larger step loses nothing but round-off.)
      const double eps_v = 1e-4;
      Vector vp = v, vm = v;
      vp[k] += eps_v;
      vm[k] -= eps_v;
      model.force(0.0, x, vp, fp);
      model.force(0.0, x, vm, fm);
      const Vector column_v = (fp - fm) / (2 * eps_v);
      worst_v = std::max(worst_v, (Kv.col(k) - column_v).norm() / (1.0 + column_v.norm()));
    }
    std::cout << dim << "-D Jacobian check: dF/dx rel error " << worst_x << ", dF/dv " << worst_v
              << " (" << x.size() << " unknowns)\n";
    EXPECT_LT(worst_x, 1e-6) << dim << "-D";
    EXPECT_LT(worst_v, 1e-6) << dim << "-D";
  }
}

// The pattern follows the neighbours: after the particles rearrange, the
// Jacobian comes on a new pattern (a new version) and is still exact.
TEST(FluidForces, PatternFollowsTheNeighbours) {
  const Model model(testing::fluid_blob(2, 40, 5, 0.05));
  ASSERT_TRUE(model.pattern_varies());
  const Vector x = model.initial_positions(), v = model.initial_velocities();
  SparseMatrix dfdx, dfdv;
  model.jacobians(0.0, x, v, &dfdx, &dfdv);
  EXPECT_EQ(model.pattern_version(), 0);
  // Mirror half the blob onto the other: new pairs everywhere.
  Vector y = x;
  for (Eigen::Index p = 0; p < y.size() / 2; ++p) y[2 * p] = -y[2 * p] * 0.7 + 0.013 * (p % 5);
  model.jacobians(0.0, y, v, &dfdx, &dfdv);
  EXPECT_EQ(model.pattern_version(), 1);
  EXPECT_EQ(dfdx.nonZeros(), model.jacobian_pattern().nonZeros());
  const Eigen::MatrixXd K(dfdx);
  const double eps = 1e-7;
  Vector fp, fm;
  double worst = 0.0;
  for (Eigen::Index k = 0; k < y.size(); ++k) {
    Vector yp = y, ym = y;
    yp[k] += eps;
    ym[k] -= eps;
    model.force(0.0, yp, v, fp);
    model.force(0.0, ym, v, fm);
    const Vector column = (fp - fm) / (2 * eps);
    worst = std::max(worst, (K.col(k) - column).norm() / (1.0 + column.norm()));
  }
  EXPECT_LT(worst, 1e-6);
  // A small move keeps the pattern (the skin).
  Vector z = y;
  z[0] += 1e-4;
  model.jacobians(0.0, z, v, &dfdx, &dfdv);
  EXPECT_EQ(model.pattern_version(), 1);
}

// ---- The built-in scenes ----

struct Samples {
  std::vector<double> t;
  std::vector<Vector> x;
};

class Recorder final : public Observer {
 public:
  explicit Recorder(Samples& run) : run_(run) {}
  void observe(double t, const Vector& x, const Vector&) override {
    run_.t.push_back(t);
    run_.x.push_back(x);
  }

 private:
  Samples& run_;
};

Samples simulate_scene(const Model& model, const std::string& integrator, double dt,
                   double t_end, int every) {
  RunSettings s;
  s.integrator = integrator;
  s.dt = dt;
  s.t_end = t_end;
  s.every = every;
  Samples run;
  Recorder recorder(run);
  const RunResult result = simulate(model, s, {&recorder});
  EXPECT_EQ(result.status, RunStatus::kCompleted) << result.failure;
  return run;
}

// The explicit step: CFL and acoustic, h = 0.25 (kernel h) / c (Monaghan 1994).
double explicit_step(const Scene& s) {
  const Fluid& f = s.get<Fluids>().front();
  return 0.25 * kSmoothingPerSpacing * f.spacing / f.speed_of_sound;
}

TEST(FluidScenes, TankSettlesToHydrostaticPressure) {
  const Scene scene = make_builtin_scene(
      "tank", {{"width", "0.2"}, {"depth", "0.2"}, {"spacing", "0.0125"}, {"sound", "15"},
               {"alpha", "0.3"}});
  const Model model(scene);
  const Fluid& fluid = scene.get<Fluids>().front();
  const double dt = explicit_step(scene);
  const double g = 9.81, depth = 0.2, l = fluid.spacing;
  // Settling: many acoustic periods 4 H / c and a few gravity-wave periods.
  const Samples run = simulate_scene(model, "symplectic-euler", dt, 1.0, 100000);
  const Eigen::MatrixXd x = model.scene_positions(run.x.back());
  std::vector<double> flat(static_cast<std::size_t>(x.size()));
  for (Eigen::Index s = 0; s < x.rows(); ++s) {
    for (Eigen::Index r = 0; r < x.cols(); ++r) flat[static_cast<std::size_t>(s * x.cols() + r)] = x(s, r);
  }
  const FluidFields fields = fluid_fields(scene, fluid, flat.data());
  // The density: of the particles a kernel support (2h) or more below the
  // surface (nearer, the sum misses the neighbours above it: a free
  // surface's summation density is not the water's).
  double surface = 0.0;
  for (int s = 0; s < fluid.count; ++s) {
    if (!scene.particles[static_cast<std::size_t>(s)].fixed) surface = std::max(surface, x(s, 1));
  }
  const double support = 2.0 * kSmoothingPerSpacing * l;
  double bottom = 0.0, worst_density = 0.0;
  int bottom_count = 0, interior = 0;
  for (int s = 0; s < fluid.count; ++s) {
    if (scene.particles[static_cast<std::size_t>(s)].fixed) continue;
    const double rho = fields.density[static_cast<std::size_t>(s)];
    if (x(s, 1) < surface - support) {
      worst_density = std::max(worst_density, std::abs(rho / fluid.density - 1.0));
      ++interior;
    }
    if (x(s, 1) < l) {
      bottom += fields.pressure[static_cast<std::size_t>(s)];
      ++bottom_count;
    }
  }
  ASSERT_GT(bottom_count, 0);
  ASSERT_GT(interior, fluid.count / 4);
  bottom /= bottom_count;
  // The bottom layer's centres sit l/2 above the floor.
  const double expected = fluid.density * g * (depth - 0.5 * l);
  std::cout << "tank: bottom pressure " << bottom << " Pa against rho0 g depth " << expected
            << " (" << 100.0 * (bottom / expected - 1.0) << " %), density within "
            << 100.0 * worst_density << " % of rho0\n";
  EXPECT_NEAR(bottom / expected, 1.0, 0.05);
  EXPECT_LT(worst_density, 0.01);
}

TEST(FluidScenes, SloshingPeriodMatchesLinearTheory) {
  const double width = 0.4, depth = 0.2;
  const Scene scene = make_builtin_scene(
      "sloshing", {{"width", "0.4"}, {"depth", "0.2"}, {"spacing", "0.02"},
                   {"amplitude", "0.008"}, {"alpha", "0.02"}});
  const Model model(scene);
  const double g = 9.81, k = std::numbers::pi / width;
  const double period = 2.0 * std::numbers::pi / std::sqrt(g * k * std::tanh(k * depth));
  const double dt = explicit_step(scene);
  const int every = std::max(1, static_cast<int>(0.002 / dt));
  const Samples run = simulate_scene(model, "symplectic-euler", dt, 2.2 * period, every);
  // The water's horizontal centre of mass swings with the first mode.
  std::vector<double> centre;
  for (const Vector& x : run.x) {
    const Eigen::MatrixXd p = model.scene_positions(x);
    double sum = 0.0;
    int n = 0;
    for (Eigen::Index s = 0; s < p.rows(); ++s) {
      if (scene.particles[static_cast<std::size_t>(s)].fixed) continue;
      sum += p(s, 0);
      ++n;
    }
    centre.push_back(sum / n - 0.5 * width);
  }
  // Downward zero crossings (linear interpolation): one per period.
  std::vector<double> crossings;
  for (std::size_t k2 = 1; k2 < centre.size(); ++k2) {
    if (centre[k2 - 1] > 0.0 && centre[k2] <= 0.0) {
      const double f = centre[k2 - 1] / (centre[k2 - 1] - centre[k2]);
      crossings.push_back(run.t[k2 - 1] + f * (run.t[k2] - run.t[k2 - 1]));
    }
  }
  ASSERT_GE(crossings.size(), 2u);
  const double measured = crossings[1] - crossings[0];
  std::cout << "sloshing: period " << measured << " s against linear theory " << period << " s ("
            << 100.0 * (measured / period - 1.0) << " %)\n";
  EXPECT_NEAR(measured / period, 1.0, 0.05);
}

// Martin and Moyce (1952), Table 2 (experiments/reference/): Z(T).
std::vector<std::pair<double, double>> martin_moyce() {
  std::ifstream in(std::string(SPRINGLAB_TEST_DATA) + "/../../experiments/reference/martin-moyce-1952.csv");
  std::vector<std::pair<double, double>> points;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 'T') continue;
    std::istringstream fields(line);
    double T = 0.0, Z = 0.0;
    char comma = 0;
    fields >> T >> comma >> Z;
    points.emplace_back(T, Z);
  }
  return points;
}

double interpolate(const std::vector<std::pair<double, double>>& table, double T) {
  for (std::size_t k = 1; k < table.size(); ++k) {
    if (table[k].first >= T) {
      const double f = (T - table[k - 1].first) / (table[k].first - table[k - 1].first);
      return table[k - 1].second + f * (table[k].second - table[k - 1].second);
    }
  }
  return table.back().second;
}

TEST(FluidScenes, DamBreakFrontAgainstRitterAndMartinMoyce) {
  const auto table = martin_moyce();
  ASSERT_EQ(table.size(), 15u);
  const double a = 0.1, g = 9.81;
  const Scene scene = make_builtin_scene("dam-break", {{"a", "0.1"}, {"spacing", "0.01"}});
  const Model model(scene);
  const double l = scene.get<Fluids>().front().spacing;
  const double dt = explicit_step(scene);
  const double time_scale = std::sqrt(2.0 * g / a);  // T = t sqrt(2 g / a)
  const int every = std::max(1, static_cast<int>(0.002 / dt));
  const Samples run = simulate_scene(model, "symplectic-euler", dt, 2.6 / time_scale, every);
  // The front: the water's largest x plus half a spacing (a particle's extent).
  std::vector<double> front;
  for (const Vector& x : run.x) {
    const Eigen::MatrixXd p = model.scene_positions(x);
    double most = 0.0;
    for (Eigen::Index s = 0; s < p.rows(); ++s) {
      if (!scene.particles[static_cast<std::size_t>(s)].fixed) most = std::max(most, p(s, 0));
    }
    front.push_back(most + 0.5 * l);
  }
  // Ritter's dry-bed front speed 2 sqrt(g H), H = 2a the column's height:
  // the shallow-water bound no front can pass (Ritter 1892).
  const double ritter = 2.0 * std::sqrt(g * 2.0 * a);
  double fastest = 0.0;
  for (std::size_t k = 1; k < front.size(); ++k) {
    fastest = std::max(fastest, (front[k] - front[k - 1]) / (run.t[k] - run.t[k - 1]));
  }
  // Z at T = 2.
  double Z2 = 0.0;
  for (std::size_t k = 1; k < front.size(); ++k) {
    if (run.t[k] * time_scale >= 2.0) {
      const double f = (2.0 / time_scale - run.t[k - 1]) / (run.t[k] - run.t[k - 1]);
      Z2 = (front[k - 1] + f * (front[k] - front[k - 1])) / a;
      break;
    }
  }
  const double reference = interpolate(table, 2.0);
  std::cout << "dam break: fastest front " << fastest << " m/s (Ritter " << ritter
            << "), Z(T = 2) = " << Z2 << " against Martin and Moyce " << reference << " ("
            << 100.0 * (Z2 / reference - 1.0) << " %)\n";
  EXPECT_LT(fastest, ritter);
  EXPECT_NEAR(Z2 / reference, 1.0, 0.15);
}

// Every integrator runs a small fluid or refuses it at t = 0 with a reason
// naming itself.
TEST(FluidScenes, EveryIntegratorRunsOrRefusesAtTheStart) {
  const Scene scene = make_builtin_scene(
      "tank", {{"width", "0.1"}, {"depth", "0.05"}, {"spacing", "0.0125"}});
  const Model model(scene);
  const double dt = explicit_step(scene);
  int ran = 0;
  for (const std::string& name : integrator_names()) {
    RunSettings s;
    s.integrator = name;
    s.dt = dt;
    s.t_end = 10 * dt;
    const RunResult r = simulate(model, s, {});
    if (r.status == RunStatus::kFailed) {
      EXPECT_EQ(r.diverged_at.value_or(-1.0), 0.0) << name << ": " << r.failure;
      EXPECT_EQ(r.failure.rfind(name + ":", 0), 0u) << r.failure;
      std::cout << "refused: " << r.failure << "\n";
    } else {
      EXPECT_EQ(r.status, RunStatus::kCompleted) << name;
      ++ran;
    }
  }
  EXPECT_GE(ran, 15);
}

// The block form of a fluid: a box filled at the spacing, each cell's
// centre a particle, masses such that an interior particle sits at rho0;
// written back as a [first, count] range after the file's particles, it
// reads back to the same scene.
TEST(FluidScenes, BoxBlockFillsItsLatticeAtRestDensity) {
  const std::string text = R"({"dimension": 2, "gravity": [0, -9.81],
    "particles": [{"x": [-1, -1], "fixed": true}], "springs": [],
    "fluids": [{"box": [[0, 0], [0.1, 0.06]], "density": 1000, "spacing": 0.01,
                "speed_of_sound": 10, "viscosity": 0.001}]})";
  const Scene scene = parse_scene(text, "box.json");
  ASSERT_EQ(scene.particles.size(), 1u + 10u * 6u);
  const Fluid& f = scene.get<Fluids>().front();
  EXPECT_EQ(f.first, 1);
  EXPECT_EQ(f.count, 60);
  EXPECT_EQ(scene.particles[1].x, Eigen::Vector3d(0.005, 0.005, 0.0));
  EXPECT_EQ(scene.particles[60].x, Eigen::Vector3d(0.095, 0.055, 0.0));
  EXPECT_FALSE(scene.particles[60].fixed);
  std::vector<double> flat;
  for (const Particle& p : scene.particles) {
    flat.push_back(p.x.x());
    flat.push_back(p.x.y());
  }
  const FluidFields fields = fluid_fields(scene, f, flat.data());
  // Particle (4, 2) of the 10 x 6 block has every lattice neighbour
  // within 2h = 2.6 l in the block: density rho0.
  EXPECT_NEAR(fields.density[2 * 10 + 4] / 1000.0, 1.0, 1e-12);
  const Scene again = parse_scene(scene_to_json(scene), "again.json");
  EXPECT_EQ(scene_to_json(again), scene_to_json(scene));
  EXPECT_EQ(again.get<Fluids>().front().first, 1);
}

// ---- Position-based fluids (xpbd; models/fluids/fluid_density_projection.cc) ----

// The system's projections, as xpbd reads them.
std::vector<std::unique_ptr<PositionProjection>> projections_of(const Model& model) {
  std::vector<DistanceConstraint> constraints;
  std::vector<ProjectiveElement> elements;
  std::vector<std::unique_ptr<PositionProjection>> projections;
  Refusal why;
  EXPECT_TRUE(model.position_based_form(constraints, elements, projections, why)) << why.text;
  return projections;
}

// Without walls, every pair's moves are equal and opposite in momentum
// (the tensile-instability term too: it is mass-weighted), and the
// projections lower the compression.
TEST(FluidPositionBased, ProjectionKeepsMomentumAndRelievesCompression) {
  for (int dim : {2, 3}) {
    const Scene scene = testing::fluid_blob(dim, dim == 2 ? 150 : 120, 9, 0.0);
    const Model model(scene);
    auto projections = projections_of(model);
    ASSERT_EQ(projections.size(), 1u);
    Vector x = model.initial_positions();
    const Vector x0 = x;
    projections[0]->begin(x);
    const double hs = 0.1;  // a~ small beside the constraints' stiffness
    auto compression = [&](const Vector& y) {
      std::vector<double> flat(y.data(), y.data() + y.size());
      const FluidFields fields = fluid_fields(scene, scene.get<Fluids>().front(), flat.data());
      double sum = 0.0;
      for (double rho : fields.density) sum += std::max(rho / scene.get<Fluids>().front().density - 1.0, 0.0);
      return sum;
    };
    projections[0]->project(x, hs);
    Eigen::Vector3d momentum = Eigen::Vector3d::Zero();
    double moved = 0.0;
    for (Eigen::Index k = 0; k < x.size(); ++k) {
      const double m = model.mass()[k];
      momentum[k % dim] += m * (x[k] - x0[k]);
      moved += m * std::abs(x[k] - x0[k]);
    }
    ASSERT_GT(moved, 0.0);
    EXPECT_LT(momentum.norm(), 1e-12 * moved) << dim << "-D";
    for (int it = 0; it < 20; ++it) projections[0]->project(x, hs);
    std::cout << dim << "-D blob: sum of compressions " << compression(x0) << " -> "
              << compression(x) << " after 21 projections\n";
    EXPECT_LT(compression(x), 0.5 * compression(x0)) << dim << "-D";
  }
}

// Interior density of the free particles a kernel support or more below
// the surface, at the run's last state: the largest |rho / rho0 - 1|.
double interior_density_error(const Model& model, const Vector& x_free) {
  const Scene& scene = model.scene();
  const Fluid& fluid = scene.get<Fluids>().front();
  const Eigen::MatrixXd x = model.scene_positions(x_free);
  std::vector<double> flat(static_cast<std::size_t>(x.size()));
  for (Eigen::Index s = 0; s < x.rows(); ++s) {
    for (Eigen::Index r = 0; r < x.cols(); ++r) flat[static_cast<std::size_t>(s * x.cols() + r)] = x(s, r);
  }
  const FluidFields fields = fluid_fields(scene, fluid, flat.data());
  double surface = -INFINITY;
  for (int s = 0; s < fluid.count; ++s) {
    if (!scene.particles[static_cast<std::size_t>(s)].fixed) surface = std::max(surface, x(s, 1));
  }
  const double support = 2.0 * kSmoothingPerSpacing * fluid.spacing;
  double worst = 0.0;
  int interior = 0;
  for (int s = 0; s < fluid.count; ++s) {
    if (scene.particles[static_cast<std::size_t>(s)].fixed || x(s, 1) >= surface - support) continue;
    worst = std::max(worst, std::abs(fields.density[static_cast<std::size_t>(s)] / fluid.density - 1.0));
    ++interior;
  }
  EXPECT_GT(interior, 0);
  return worst;
}

TEST(FluidPositionBased, TankAtRestKeepsItsDensity) {
  const Scene scene = make_builtin_scene(
      "tank", {{"width", "0.2"}, {"depth", "0.2"}, {"spacing", "0.0125"}});
  const Model model(scene);
  RunSettings s;
  s.integrator = "xpbd";
  s.dt = 1.0 / 120.0;
  s.t_end = 1.0;
  s.every = 1000;
  s.options.substeps = 8;
  Samples run;
  Recorder recorder(run);
  const RunResult r = simulate(model, s, {&recorder});
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  const double worst = interior_density_error(model, run.x.back());
  // The water stays in its box, below its height plus a spacing.
  const Eigen::MatrixXd x = model.scene_positions(run.x.back());
  double lowest = INFINITY, highest = -INFINITY;
  for (Eigen::Index p = 0; p < x.rows(); ++p) {
    if (scene.particles[static_cast<std::size_t>(p)].fixed) continue;
    lowest = std::min(lowest, x(p, 1));
    highest = std::max(highest, x(p, 1));
  }
  std::cout << "PBF tank after 1 s: interior density within " << 100.0 * worst
            << " % of rho0, water between y = " << lowest << " and " << highest << " m\n";
  EXPECT_LT(worst, 0.04);
  EXPECT_GT(lowest, 0.0);
  EXPECT_LT(highest, 0.2 + 0.0125);
}

TEST(FluidPositionBased, DamBreakFrontStaysBelowRittersBound) {
  const double a = 0.1, g = 9.81;
  const Scene scene = make_builtin_scene("dam-break", {{"a", "0.1"}, {"spacing", "0.01"}});
  const Model model(scene);
  const double l = 0.01, time_scale = std::sqrt(2.0 * g / a);
  RunSettings s;
  s.integrator = "xpbd";
  s.dt = 0.004;
  s.t_end = 0.2;
  s.options.substeps = 8;
  Samples run;
  Recorder recorder(run);
  const RunResult r = simulate(model, s, {&recorder});
  ASSERT_EQ(r.status, RunStatus::kCompleted) << r.failure;
  std::vector<double> front;
  for (const Vector& x : run.x) {
    const Eigen::MatrixXd p = model.scene_positions(x);
    double most = 0.0;
    for (Eigen::Index k = 0; k < p.rows(); ++k) {
      if (!scene.particles[static_cast<std::size_t>(k)].fixed) most = std::max(most, p(k, 0));
    }
    front.push_back(most + 0.5 * l);
  }
  const double ritter = 2.0 * std::sqrt(g * 2.0 * a);
  double fastest = 0.0, Z2 = 0.0;
  for (std::size_t k = 1; k < front.size(); ++k) {
    fastest = std::max(fastest, (front[k] - front[k - 1]) / (run.t[k] - run.t[k - 1]));
    if (Z2 == 0.0 && run.t[k] * time_scale >= 2.0) {
      const double f = (2.0 / time_scale - run.t[k - 1]) / (run.t[k] - run.t[k - 1]);
      Z2 = (front[k - 1] + f * (front[k] - front[k - 1])) / a;
    }
  }
  const double reference = interpolate(martin_moyce(), 2.0);
  std::cout << "PBF dam break: fastest front " << fastest << " m/s (Ritter " << ritter
            << "), Z(T = 2) = " << Z2 << " against Martin and Moyce " << reference << "\n";
  EXPECT_LT(fastest, ritter);
  EXPECT_NEAR(Z2 / reference, 1.0, 0.15);
}

// The other fast solvers refuse a fluid, naming the one that runs it.
TEST(FluidPositionBased, ProjectiveDynamicsRefusesNamingXpbd) {
  const Model model(make_builtin_scene(
      "tank", {{"width", "0.1"}, {"depth", "0.05"}, {"spacing", "0.0125"}}));
  RunSettings s;
  s.integrator = "projective-dynamics";
  s.dt = 0.01;
  s.t_end = 0.02;
  const RunResult r = simulate(model, s, {});
  EXPECT_EQ(r.status, RunStatus::kFailed);
  EXPECT_NE(r.failure.find("xpbd runs them as position-based fluids"), std::string::npos)
      << r.failure;
}

}  // namespace
}  // namespace springlab::test_fluids
