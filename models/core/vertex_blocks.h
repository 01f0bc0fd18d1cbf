// Vertex block descent's view of a system (vbd, integrators/fast/vbd.h; Chen,
// Macklin et al., "Vertex Block Descent", SIGGRAPH 2024): the forces one
// particle feels from the elements around it, and their derivatives with
// respect to that particle alone, at a state. VBD minimizes implicit
// Euler's incremental potential one particle at a time,
//
//   G_i(x_i) = m_i / (2 h^2) |x_i - x_n,i - h v_n,i|^2 + E_i(x)   (the rest held),
//
// E_i the energies of the elements around particle i (springs, triangles,
// tetrahedra, contact planes, gravity), by a 3 x 3 Newton step: its
// gradient needs F_i, the force on i, and its Hessian the diagonal blocks
// dF_i/dx_i and dF_i/dv_i (the damping forces act through v = (x - x_n)/h).
// Nothing here knows of time stepping: the view gives forces and their
// blocks; the integrator adds the inertia.
//
// The states: positions and velocities of *all* particles, free ones first
// (the integrator's unknowns, in their order), then the fixed ones at their
// places (fill_fixed gives those); fixed particles have velocity 0.
//
// A system that has this view hands it out through FastSolverViews::
// vertex_block_view() (models/core/fast_solver_views.h); one whose forces have
// no per-particle form (rigid bodies, fluids, whose couplings follow the
// state) says why in vertex_form.
#pragma once

#include <string>

#include "models/core/mechanical_system.h"
#include "models/core/refusal.h"

namespace springlab {

// Where the blocks of `count` particles go, particle k at f + k d and
// dfdx + k d^2, dfdv + k d^2 (d the dimension; each block row-major).
struct VertexBlocks {
  double* f = nullptr;     // F_i: the force on particle i
  double* dfdx = nullptr;  // dF_i/dx_i
  double* dfdv = nullptr;  // dF_i/dv_i; nullptr when no force depends on v
};

class VertexBlockView {
 public:
  virtual ~VertexBlockView() = default;

  // False, with why (one sentence for the user, and no scene remedy: no
  // setting gives these forces a per-particle form), when some force has no
  // per-particle form.
  virtual bool vertex_form(Refusal& why) const = 0;
  // d: the dimension of a particle (dofs = free particles x d).
  virtual int dimension_of_state() const = 0;
  // All particles, free and fixed: the states' length is this times d.
  virtual Eigen::Index all_particles() const = 0;
  // Writes the fixed particles' places into the tail of x_all (after the
  // free particles' d x free entries).
  virtual void fill_fixed(Vector& x_all) const = 0;
  // Whether some force depends on v (else vertex_blocks ignores v_all and
  // dfdv).
  virtual bool reads_velocity() const = 0;
  // The forces that depend on neither x nor v (gravity) on the free
  // particles: dofs entries into f.
  virtual void constant_force(double* f) const = 0;

  // For each of `count` free particles (indices into the free particles),
  // sets out's F_i, dF_i/dx_i and dF_i/dv_i at (t, x_all, v_all): the sum
  // over every element that touches particle i. With `definite`, each
  // element's share of dF_i/dx_i is its nearest negative semidefinite block
  // (a compressed spring's negative transverse stiffness dropped, an
  // element's 3 x 3 block with its positive eigenvalues set to zero), so
  // that m_i / h^2 I - dF_i/dx_i - dF_i/dv_i / h is positive definite.
  virtual void vertex_blocks(double t, const double* x_all, const double* v_all,
                             const int* particles, int count, bool definite,
                             const VertexBlocks& out) const = 0;

  // The largest a (+infinity when nothing limits it) such that particle i
  // moved alone by a dx, from x_all, stays where every energy is finite:
  // a barrier's gap stays open (it closes at d / (-n.dx)), a solid element
  // whose material has no energy at J <= 0 (neo-Hookean) stays uninverted
  // (det(F + a dx g^T) = det F (1 + a g^T F^-1 dx) reaches 0 at a =
  // -1 / (g^T F^-1 dx)). The integrator's local step cap.
  virtual double vertex_admissible_fraction(const double* x_all, int particle,
                                            const double* dx) const = 0;
};

}  // namespace springlab
