// Position-based fluids (Macklin and Mueller 2013, "Position based fluids",
// ACM TOG 32(4):104): a fluid's pressure as density constraints that the
// xpbd integrator projects (FastSolverViews::position_based_form,
// docs/integrators.md "Position-based fluids"). One constraint per free
// particle i of a fluid,
//
//   C_i = rho_i / rho0 - 1 <= 0,    rho_i = sum_j m_j W(|x_i - x_j|)
//
// (their eq. 1-2, with the particles' masses kept), unilateral as the Tait
// law is (fluids.h: no tension; a free surface's particles, short of
// neighbours, would otherwise clump). Its gradients, with
// G_ij = grad_i W(|x_i - x_j|):
//
//   grad_i C_i = (1/rho0) sum_j m_j G_ij,   grad_k C_i = -(1/rho0) m_k G_ik.
//
// XPBD's update (Macklin, Mueller and Chentanez 2016, eq. 18) of each
// multiplier, one constraint after the other from the positions the ones
// before it left (a Gauss-Seidel pass in the fluid's particle order, as
// xpbd projects springs; the paper's parallel Jacobi pass overshoots where
// every particle's constraint shares most neighbours with the next one's
// unless it is relaxed):
//
//   dlambda_i = (-C_i - a~_i lambda_i) / (sum_k w_k |grad_k C_i|^2 + a~_i),
//   lambda_i <= 0 (the constraint pushes, never pulls),
//   x_k += w_k dlambda_i grad_k C_i  for k = i and its free neighbours,
//
// so that x_i moves by (dlambda_i / rho0) sum_j (m_j / m_i) G_ij and a
// neighbour j by -(dlambda_i / rho0) G_ij: summed over i, the paper's
//
//   dx_i = (1/rho0) sum_j (lambda_i m_j / m_i + lambda_j + s_ij) G_ij
//
// (their eq. 12 with masses; lambda_j = 0 for a wall particle, which has
// no constraint; between free particles each projection keeps momentum,
// sum_k m_k dx_k = 0). The compliance is the Tait law's own near rho0: its
// energy m e(rho) = m c^2 C^2 / 2 + O(C^3) (fluids.h) is XPBD's C^2 /
// (2 alpha) with alpha_i = 1 / (m_i c^2), so a~_i = 1 / (m_i c^2 h_s^2):
// a large c gives the paper's incompressible fluid, the scene's c the same
// compression as SPH. s_ij is the paper's tensile-instability correction
// (their eq. 13-14), an artificial pressure after Monaghan (2000):
//
//   s_ij = -k (W(r_ij) / W(dq))^n Lambda_i,  k = 0.03, n = 4, dq = 0.2 x 2h,
//   Lambda_i = 1 / (1 / Lambda + a~_i),
//
// with Lambda = 1 / (sum_k w_k |grad_k C|^2) of an interior particle of the
// lattice at rest: Lambda_i is the multiplier the projection gives a unit
// violation, so that s_ij acts as an extra compression k (W / W(dq))^n would,
// through the same compliance (the paper's constants are for its own units;
// this keeps them dimensionless, and with the compliance in Lambda_i a
// substep of half the length moves it about a quarter as far where the
// compliance dominates, as a force would). The
// paper's n and dq, and k = 0.03 rather than its 0.1: at 0.1 the tank at rest
// (tests/test_fluids.cc, 8 substeps) swells to 8.5 % below rho0 inside, at
// 0.03 it stays within 1.5 % below and 3 % above. For unequal masses it
// is weighted 2 m_j / (m_i + m_j) so that the pair's moves keep momentum
// (half of it at i's turn, half at j's; all of it at i's for a wall
// particle j). The neighbours are
// those within the support 2h at the substep's predicted positions
// (begin()), as in the paper's Algorithm 1.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "models/fluids/fluid_forces.h"
#include "models/fluids/fluids.h"
#include "models/fluids/sph_particles.h"

namespace springlab {
namespace {

constexpr double kCorrectionK = 0.03;  // k
constexpr int kCorrectionN = 4;        // n
constexpr double kCorrectionQ = 0.2;   // dq / (2h)

class FluidDensityProjection final : public PositionProjection {
 public:
  FluidDensityProjection(std::vector<SphParticles> fluids, std::vector<double> x_all, int dim,
                         int free_particles)
      : fluids_(std::move(fluids)), x_all_(std::move(x_all)), dim_(dim), free_(free_particles) {
    for (const SphParticles& f : fluids_) scale_.push_back(unit_multiplier(f));
  }

  void begin(const Vector& x) override {
    std::copy(x.data(), x.data() + static_cast<std::ptrdiff_t>(free_) * dim_, x_all_.begin());
    lambda_.resize(fluids_.size());
    neighbours_.resize(fluids_.size());
    for (std::size_t f = 0; f < fluids_.size(); ++f) {
      SphParticles& fluid = fluids_[f];
      fluid.update(x_all_.data());
      lambda_[f].assign(static_cast<std::size_t>(fluid.size()), 0.0);
      // Each particle's partners, both ways round (CSR).
      Neighbours& nb = neighbours_[f];
      nb.start.assign(static_cast<std::size_t>(fluid.size()) + 1, 0);
      for (const auto& [a, b] : fluid.pairs()) {
        ++nb.start[static_cast<std::size_t>(a) + 1];
        ++nb.start[static_cast<std::size_t>(b) + 1];
      }
      for (std::size_t a = 0; a < static_cast<std::size_t>(fluid.size()); ++a) {
        nb.start[a + 1] += nb.start[a];
      }
      nb.partner.resize(static_cast<std::size_t>(nb.start.back()));
      std::vector<int> fill(nb.start.begin(), nb.start.end() - 1);
      for (const auto& [a, b] : fluid.pairs()) {
        nb.partner[static_cast<std::size_t>(fill[static_cast<std::size_t>(a)]++)] = b;
        nb.partner[static_cast<std::size_t>(fill[static_cast<std::size_t>(b)]++)] = a;
      }
    }
  }

  void project(Vector& x, double hs) override {
    if (dim_ == 2) project_d<2>(x, hs); else project_d<3>(x, hs);
  }

 private:
  // Lambda: 1 / (sum_k w_k |grad_k C|^2) for an interior particle of the
  // square (cubic) lattice of the fluid's spacing, with its mean mass.
  double unit_multiplier(const SphParticles& f) const {
    double mass = 0.0;
    for (int a = 0; a < f.size(); ++a) mass += f.mass(a);
    mass /= std::max(1, f.size());
    const CubicSpline& w = f.kernel();
    const double l = w.h / kSmoothingPerSpacing;
    const int reach = 3;
    double sum = 0.0;  // sum_k |G_0k|^2 (grad_0 C_0 vanishes by symmetry)
    for (int i = -reach; i <= reach; ++i) {
      for (int j = -reach; j <= reach; ++j) {
        for (int k = dim_ == 3 ? -reach : 0; k <= (dim_ == 3 ? reach : 0); ++k) {
          const double r = l * std::sqrt(double(i * i + j * j + k * k));
          if (r == 0.0) continue;
          const double g = w.slope(r);
          sum += g * g;
        }
      }
    }
    const double rho0 = f.eos().rho0;
    // sum_k (1/m) (m g / rho0)^2 = m / rho0^2 sum g^2.
    return sum > 0.0 ? rho0 * rho0 / (mass * sum) : 0.0;
  }

  // One Gauss-Seidel pass: each water particle's constraint in turn, from
  // the positions the ones before it left.
  template <int D>
  void project_d(Vector& x, double hs) {
    for (std::size_t f = 0; f < fluids_.size(); ++f) {
      const SphParticles& fluid = fluids_[f];
      const Neighbours& nb = neighbours_[f];
      const CubicSpline& w = fluid.kernel();
      const double rho0 = fluid.eos().rho0, c = fluid.eos().c;
      const double wq = w.value(kCorrectionQ * w.support());
      auto position = [&](int a) -> double* {
        const int p = fluid.index(a);
        return p < free_ ? x.data() + p * D : x_all_.data() + p * D;
      };
      std::vector<double>& lambda = lambda_[f];
      for (int a = 0; a < fluid.size(); ++a) {
        if (fluid.index(a) >= free_) continue;
        const int first = nb.start[static_cast<std::size_t>(a)];
        const int last = nb.start[static_cast<std::size_t>(a) + 1];
        const double ma = fluid.mass(a);
        double* xa = position(a);
        // rho_a, G_ab = grad_a W_ab and W_ab for each partner b.
        double rho = ma * w.value(0.0), self[D] = {}, others = 0.0;
        g_.resize(static_cast<std::size_t>((last - first) * D));
        kernel_.resize(static_cast<std::size_t>(last - first));
        for (int e = first; e < last; ++e) {
          const int b = nb.partner[static_cast<std::size_t>(e)];
          const double* xb = position(b);
          const double mb = fluid.mass(b);
          double d[D], r2 = 0.0;
          for (int r = 0; r < D; ++r) {
            d[r] = xa[r] - xb[r];
            r2 += d[r] * d[r];
          }
          const double dist = std::sqrt(r2);
          const double wk = w.value(dist), so = w.slope_over_r(dist);
          const std::size_t k = static_cast<std::size_t>(e - first);
          kernel_[k] = wk;
          rho += mb * wk;
          double g2 = 0.0;
          for (int r = 0; r < D; ++r) {
            g_[k * D + r] = so * d[r];
            g2 += so * d[r] * so * d[r];
            self[r] += mb * so * d[r] / rho0;  // grad_a C_a
          }
          // w_b |grad_b C_a|^2 = (1/m_b) (m_b / rho0)^2 |G_ab|^2.
          if (fluid.index(b) < free_) others += mb / (rho0 * rho0) * g2;
        }
        const double C = std::max(rho / rho0 - 1.0, 0.0);
        const double compliance = 1.0 / (ma * c * c * hs * hs);
        double self2 = 0.0;
        for (int r = 0; r < D; ++r) self2 += self[r] * self[r];
        double& la = lambda[static_cast<std::size_t>(a)];
        double dlambda = (-C - compliance * la) / (self2 / ma + others + compliance);
        dlambda = std::min(dlambda, -la);  // lambda + dlambda <= 0
        la += dlambda;
        // The multiplier of a unit violation, with the compliance.
        const double unit = 1.0 / (1.0 / scale_[f] + compliance);
        // x_k += w_k dlambda grad_k C_a, and half of each pair's
        // artificial pressure (the other half when b's turn comes).
        for (int r = 0; r < D; ++r) xa[r] += dlambda * self[r] / ma;
        for (int e = first; e < last; ++e) {
          const int b = nb.partner[static_cast<std::size_t>(e)];
          const std::size_t k = static_cast<std::size_t>(e - first);
          const double mb = fluid.mass(b);
          const double s = -kCorrectionK * std::pow(kernel_[k] / wq, kCorrectionN) * unit;
          // grad_b C_a = -(m_b / rho0) G_ab: x_b moves by -(dlambda / rho0) G_ab.
          // (A wall particle has no turn: a takes the whole of it.)
          const bool b_free = fluid.index(b) < free_;
          const double along_a = (b_free ? 0.5 : 1.0) * 2.0 * mb / (ma + mb) * s / rho0;
          const double along_b = b_free ? dlambda / rho0 + 0.5 * 2.0 * ma / (ma + mb) * s / rho0
                                        : 0.0;
          double* xb = position(b);
          for (int r = 0; r < D; ++r) {
            xa[r] += along_a * g_[k * D + r];
            if (b_free) xb[r] -= along_b * g_[k * D + r];
          }
        }
      }
    }
  }

  std::vector<SphParticles> fluids_;
  std::vector<double> x_all_;  // every particle, internal order: the fixed ones' places
  int dim_, free_;
  std::vector<double> scale_;  // Lambda per fluid
  std::vector<std::vector<double>> lambda_;
  struct Neighbours {
    std::vector<int> start, partner;
  };
  std::vector<Neighbours> neighbours_;  // per fluid, found in begin()
  std::vector<double> g_, kernel_;      // the current constraint's pairs
};

}  // namespace

std::unique_ptr<PositionProjection> make_fluid_density_projection(
    std::vector<SphParticles> fluids, std::vector<double> x_all, int dim, int free_particles) {
  return std::make_unique<FluidDensityProjection>(std::move(fluids), std::move(x_all), dim,
                                                  free_particles);
}

}  // namespace springlab
