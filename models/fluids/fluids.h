// Fluids in a scene (docs/physics.md "Fluids", "Scene files" key "fluids"):
// the block of scene data of the "fluid" element kind (fluid_kind.cc), whose
// pressure force is fluid_pressure_force.cc and whose viscosity the
// "fluid-viscosity" kind (fluid_viscosity_force.cc) adds.
//
// A fluid is a run of the scene's particles [first, first + count) treated
// by weakly compressible smoothed particle hydrodynamics (Monaghan 1994,
// J. Comput. Phys. 110:399; Monaghan 2005, Rep. Prog. Phys. 68:1703): its
// free particles are the fluid, its fixed particles the walls (the dynamic
// boundary particles of Crespo, Gomez-Gesteira and Dalrymple 2007, Comput.
// Mater. Contin. 5:173: they take part in the density summation and carry a
// pressure like the fluid's, but do not move). Two fluids do not see each
// other. Contact planes act on the fluid's free particles as on any other.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

namespace springlab {

struct Fluid {
  int first = 0;                 // scene index of its first particle
  int count = 0;                 // its number of particles
  double density = 1000.0;       // rho0 [kg/m^3]
  double spacing = 0.0;          // l, the particles' initial spacing [m]
  double speed_of_sound = 0.0;   // c [m/s]
  double viscosity = 0.0;        // nu, kinematic [m^2/s]
};

// The scene's fluids, in file order: `scene.block<Fluids>()`.
using Fluids = std::vector<Fluid>;

// At most this many fluids per scene (docs/reliability.md "Reliability").
inline constexpr std::size_t kMaxSceneFluids = 1'000;

// The smoothing length h = kSmoothingPerSpacing l (the kernel's support is
// 2h = 2.6 l: about 21 neighbours in 2-D, 74 in 3-D at the initial spacing),
// within the range h / l = 1.2 ... 1.5 common in weakly compressible SPH.
inline constexpr double kSmoothingPerSpacing = 1.3;

// The Tait equation of state with gamma = 7 (Monaghan 1994, sec. 3, after
// Batchelor 1967, for water):
//   p(rho) = B ((rho/rho0)^gamma - 1),   B = rho0 c^2 / gamma,
// taken as 0 where rho < rho0 (no tension: a free surface, whose particles
// miss neighbours in the density sum, would otherwise pull together; the
// usual treatment in SPH codes). Then
//   A(rho) = p / rho^2,   A'(rho) = (p' - 2 p / rho) / rho^2 >= 0 (gamma >= 2),
//   e(rho) = int_rho0^rho p(s) / s^2 ds
//          = (B / rho0) (((rho/rho0)^(gamma-1) - 1) / (gamma - 1) + rho0/rho - 1),
// the internal energy per unit mass, whose sum over particles m_i e(rho_i)
// is the potential of the symmetric pressure force (de/drho = p / rho^2).
struct TaitEquation {
  static constexpr double kGamma = 7.0;
  double rho0 = 1000.0;
  double c = 1.0;

  double pressure(double rho) const {
    if (!(rho > rho0)) return 0.0;
    return rho0 * c * c / kGamma * (std::pow(rho / rho0, kGamma) - 1.0);
  }
  // A = p / rho^2 and its derivative A' (0 below rho0).
  double a(double rho) const { return pressure(rho) / (rho * rho); }
  double a_slope(double rho) const {
    if (!(rho > rho0)) return 0.0;
    const double dp = c * c * std::pow(rho / rho0, kGamma - 1.0);
    return (dp - 2.0 * pressure(rho) / rho) / (rho * rho);
  }
  // e(rho), 0 below rho0.
  double energy(double rho) const {
    if (!(rho > rho0)) return 0.0;
    const double s = rho / rho0;
    const double b = rho0 * c * c / kGamma;
    return b / rho0 * ((std::pow(s, kGamma - 1.0) - 1.0) / (kGamma - 1.0) + 1.0 / s - 1.0);
  }
};

// The mass m = rho0 / sum_k W(|k| l) of each particle of a square (cubic)
// lattice of spacing l, so that an interior particle's summation density
// is rho0 exactly (the built-in scenes' and the "box" form's particles).
double lattice_mass(double rho0, double spacing, int dimension);

// The densities rho_i = sum_j m_j W(|x_i - x_j|, h) (self included) and
// pressures p(rho_i) of one fluid's particles, in its order, at the scene
// positions `x` (particle s at x[s * dimension]): for output (--vtk) and tests.
struct FluidFields {
  std::vector<double> density, pressure;
};
class Scene;
FluidFields fluid_fields(const Scene& scene, const Fluid& fluid, const double* x);

}  // namespace springlab
