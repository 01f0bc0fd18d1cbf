// Small scenes with known answers, built in code so each test states its
// physics explicitly.
#pragma once

#include <cmath>
#include <random>

#include "models/springs/drag.h"
#include "models/springs/gravity.h"
#include "models/core/scene.h"
#include "models/fluids/fluids.h"
#include "models/springs/springs.h"
#include "models/springs/wind.h"

namespace springlab::testing {

// One spring along x, fixed end at the origin, no gravity:
// x(t) = rest + amplitude cos(w t), w = sqrt(k / m). With rest = 0 (the
// default) the spring is linear in every direction, F = -k x, so the linear
// analysis (stability limits, energy factors) holds at any amplitude; with
// rest > 0 it is linear only while the mass stays on its side of the anchor.
inline Scene oscillator(double k = 100.0, double mass = 1.0, double rest = 0.0,
                        double amplitude = 0.1) {
  Scene s;
  s.name = "oscillator";
  s.dimension = 2;
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true},
                 {Eigen::Vector3d(rest + amplitude, 0, 0), Eigen::Vector3d::Zero(), mass, false}};
  s.block<Springs>() = {{0, 1, k, rest, 0.0}};
  return s;
}

// A 2-D elastic pendulum: nonlinear, swinging and stretching under gravity.
inline Scene swinging_spring() {
  Scene s;
  s.name = "swinging-spring";
  s.dimension = 2;
  s.block<Gravity>().acceleration = Eigen::Vector3d(0, -9.81, 0);
  s.particles = {{Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true},
                 {Eigen::Vector3d(0.9, -0.7, 0), Eigen::Vector3d(0.5, 0.3, 0), 1.0, false}};
  s.block<Springs>() = {{0, 1, 50.0, 1.0, 0.0}};
  return s;
}

// Every force kind at once, 3-D: a short damped chain in gusty wind with drag.
inline Scene damped_windy_chain() {
  Scene s;
  s.name = "damped-windy-chain";
  s.dimension = 3;
  s.block<Gravity>().acceleration = Eigen::Vector3d(0, -9.81, 0);
  s.block<Drag>().gamma = 0.2;
  s.block<Wind>() = Wind{Eigen::Vector3d(2.0, 0.0, 1.0), 0.3, 0.5, 2.0};
  s.particles.push_back({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true});
  for (int p = 1; p <= 3; ++p) {
    s.particles.push_back({Eigen::Vector3d(0.5 * p, -0.1 * p, 0.05 * p),
                           Eigen::Vector3d(0.1, 0.2 * p, -0.1), 0.5, false});
    s.block<Springs>().push_back({p - 1, p, 40.0, 0.45, 0.8});
  }
  return s;
}

// A 2-D chain squeezed to 30% of its rest length with a zig-zag kink: every
// spring is compressed, so its transverse stiffness k (1 - L/l) is negative
// and M - h^2 dF/dx is indefinite at moderate h.
inline Scene compressed_chain() {
  Scene s;
  s.name = "compressed-chain";
  s.dimension = 2;
  s.particles.push_back({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d::Zero(), 1.0, true});
  for (int p = 1; p <= 6; ++p) {
    s.particles.push_back({Eigen::Vector3d(0.3 * p, 0.02 * (p % 2), 0), Eigen::Vector3d::Zero(),
                           1.0, p == 6});
    s.block<Springs>().push_back({p - 1, p, 100.0, 1.0, 0.0});
  }
  return s;
}

// A random blob of fluid without walls, gravity or planes, compressed so
// that every particle has pressure (the rest density below every
// particle's), moving at random; the first `fixed` particles are walls.
inline Scene fluid_blob(int dim, int n, unsigned seed, double viscosity, int fixed = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Scene s;
  s.dimension = dim;
  const double side = std::pow(static_cast<double>(n), 1.0 / dim) * 0.1;
  for (int p = 0; p < n; ++p) {
    Particle q;
    for (int r = 0; r < dim; ++r) {
      q.x[r] = 0.5 * side * u(rng);
      q.v[r] = u(rng);
    }
    q.mass = 0.01 * (1.0 + 0.2 * u(rng));
    q.fixed = p < fixed;
    if (q.fixed) q.v.setZero();
    s.particles.push_back(q);
  }
  Fluid f;
  f.count = n;
  f.spacing = 0.1;
  f.density = 0.2 / std::pow(0.1, dim) * 0.01;
  f.speed_of_sound = 3.0;
  f.viscosity = viscosity;
  s.block<Fluids>().push_back(f);
  return s;
}

}  // namespace springlab::testing
