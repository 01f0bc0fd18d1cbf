// The pressure force's Jacobian dF/dx (fluid_pressure_force.cc, docs/physics.md
// "Fluids"), assembled into the model's pattern. With R_jk = d rho_j / d x_k
// (R_jj = sum_l m_l G_jl, R_jk = m_k G_kj for a neighbour k of j), G_ab =
// grad_a W(|x_a - x_b|) and H_ab the kernel's Hessian
// (W'/r I + (W'' - W'/r) u u^T), the pressure energy's Hessian is
//
//   d^2E/dx_a dx_k = sum_j m_j A'_j R_ja R_jk^T          (rank one per particle j)
//                  + pair terms K_ab = m_a m_b (A_a + A_b) H_ab
//                    on blocks (a, a), (b, b) (+K) and (a, b), (b, a) (-K),
//
// and dF/dx = -d^2E/dx^2. `definite` clamps the pair Hessians' eigenvalues
// (W'/r across, W'' along u) at 0: the rank-one part is semidefinite
// (A' >= 0), so the result is too (Newton's definite matrix).
//
// Two assemblies of the same sum:
//   - add_pressure_stiffness_reference: the formula as written, particle j
//     by particle j, each block found by a binary search in its column (the
//     plain version the tests hold the other to);
//   - add_pressure_stiffness: column by column. For each free particle k it
//     marks where each row particle sits in k's block column (a scatter
//     array: the pattern has whole blocks, the same rows in each of its D
//     columns), then adds the pair terms of k's neighbours and the rank-one
//     terms of the particles j in {k} and k's neighbours (R_jk != 0 only
//     there) with one indexed access per block, no search. The same terms,
//     summed in another order: equal to round-off.
#pragma once

#include <vector>

#include "models/core/force_term.h"
#include "models/fluids/sph_particles.h"

namespace springlab {

// What one assembly computes per particle and pair, kept between calls.
struct PressureHessianScratch {
  std::vector<double> a, a_slope;    // A_j, A'_j
  std::vector<double> self;          // R_jj (D per particle)
  std::vector<double> g;             // G_pq of each pair (p, q) (D per pair)
  std::vector<int> start, partner, via;  // each particle's neighbours (CSR)
  std::vector<int> rank;             // the scatter array: a row particle's place in a column
  std::vector<double> members;       // R_j, of j's members in order (D each)
  // The products' (add_pressure_stiffness_product): the update the arrays
  // above were prepared at (a fluid and its generation), each pair's block
  // K and whether it is the definite one (-1: none yet), c_j per particle.
  const SphParticles* fluid = nullptr;
  long generation = -1;
  std::vector<double> pair_k;
  int pair_k_definite = -1;
  std::vector<double> c;
};

// values += dF/dx (or its definite part) of the pressure of `fluid` at its
// last update(), on `pattern`'s values; free particles are the internal
// indices below `free_particles`. D is the dimension.
template <int D>
void add_pressure_stiffness(const SphParticles& fluid, int free_particles,
                            const SparseMatrix& pattern, bool definite, double* values,
                            PressureHessianScratch& scratch);
// out += dF/dx p (its definite part with `definite`) of the pressure of
// `fluid` at its last update(), without the matrix. With
// s_j = sum_k R_jk . p_k (the density's change along p) and
// c_j = m_j A'_j s_j,
//   (dF/dx p)_a = -sum_j c_j R_ja - sum_b K_ab (p_a - p_b),
// two passes over the pairs (reach one) where the matrix reaches two
// supports. p and out hold every particle, a at fluid.index(a) * D; p is
// read on the free particles only (the others' are 0), out written on them
// only. The per-pair quantities are prepared once per update of `fluid`.
template <int D>
void add_pressure_stiffness_product(const SphParticles& fluid, int free_particles, bool definite,
                                    const double* p, double* out,
                                    PressureHessianScratch& scratch);

template <int D>
void add_pressure_stiffness_reference(const SphParticles& fluid, int free_particles,
                                      const SparseMatrix& pattern, bool definite,
                                      double* values);

}  // namespace springlab
