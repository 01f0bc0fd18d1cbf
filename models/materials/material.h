// Hyperelastic materials (docs/physics.md "Finite elements"; the lecture's "generalized springs"):
// an energy density Psi(F) of the deformation gradient F = Ds Dm^-1, its first
// Piola-Kirchhoff stress P = dPsi/dF, and the derivative of P.
//
// F is d x k: square for solids (2 x 2 plane strain, 3 x 3 tetrahedra) and
// 3 x 2 for membranes (triangles in 3-D: in-plane stretch and shear only).
// Every formula below is written for any of these shapes, with C = F^T F
// (k x k), I_C = tr C and J the element's area or volume ratio
// (kinematics.h). Each material lives in its own file and registers a
// MaterialModel in material_registry.cc (one line).
//
// Derivatives: each model gives P and the directional derivative
// dP = dP/dF [dF] in closed form (the differential of its P formula); the
// tangent dPdF, a (d k) x (d k) matrix on vec(F) (column-major), is
// assembled from dP along each basis direction of F (dPdF below), so one
// formula per model serves every shape.
#pragma once

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

#include "models/materials/lanes.h"  // kLanes

namespace springlab {

// A matrix of at most 3 x 3, on the stack.
using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
// dPdF on vec(F): at most 9 x 9.
using Tangent = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 9, 9>;
// The same for a 3 x 3 F (a tetrahedron), fixed size.
using Tangent3 = Eigen::Matrix<double, 9, 9>;

// Lame parameters from Young's modulus E and Poisson's ratio nu
// (docs/physics.md "Finite elements"): mu = E / (2 (1 + nu)), lambda = E nu / ((1 + nu)(1 - 2 nu)).
struct Lame {
  double mu = 0.0;
  double lambda = 0.0;
};
Lame lame(double young, double poisson);

struct Derived3;  // what a model derives from a 3 x 3 F first (kinematics.h)

struct MaterialModel {
  std::string_view name;  // "neo-hookean": the "model" of a scene's material
  std::string_view formula;  // Psi, for `springlab list` and docs/physics.md
  bool membranes = true;  // defined for 3 x 2 F (linear: not, docs/physics.md "Finite elements")
  bool finite_everywhere = true;  // false: Psi = +infinity somewhere (neo-Hookean, J <= 0)
  // Poisson ratios below min_poisson leave the model without a stable rest
  // state: some deformation has less energy than rest (Psi < 0), so a solid
  // of it collapses or blows up instead of oscillating about its rest shape.
  // Refused (materials_kind.cc) with `unstable_why` saying where the energy
  // falls. -1: every ratio in (-1, 0.5) is stable. `tetrahedra_only`: only
  // 3 x 3 F (tetrahedra) have the lower state; triangles are stable.
  double min_poisson = -1.0;
  bool unstable_in_tetrahedra_only = false;
  std::string_view unstable_why = {};
  // Psi(F); +infinity where the model has no energy (neo-Hookean, J <= 0).
  double (*Psi)(const Mat& F, const Lame& m) = nullptr;
  // P = dPsi/dF (d x k).
  Mat (*P)(const Mat& F, const Lame& m) = nullptr;
  // The same P for a 3 x 3 F with fixed sizes (the tetrahedra's fast path):
  // each model writes P once, as a template on the matrix type, and
  // registers both instances. nullptr: P.
  Eigen::Matrix3d (*P3)(const Eigen::Matrix3d& F, const Lame& m) = nullptr;
  // dP = (dP/dF)[dF], the change of P along dF (d x k).
  Mat (*dP)(const Mat& F, const Mat& dF, const Lame& m) = nullptr;
  // The tetrahedra's fast path (tet_force.cc): for the rows d_1, d_2, d_3
  // of D = Dm^-1, the 9 x 9 matrix whose 3 x 3 block (i, j) is
  //   A(d_i, d_j)_rs = sum_cd (d_i)_c (dP_rc / dF_sd) (d_j)_d,
  // the tangent contracted with two rest-shape gradients (tangent3.h; the
  // "constitutive component" of the element's tangent matrix, Bonet and
  // Wood 2008), in closed form. nullptr: contracted from dPdF. The shared
  // tests check it against the contraction of the dPdF assembled from dP.
  // Any three rows serve (the blocks are bilinear in them): tet_force.cc
  // passes Dm^-1 scaled by sqrt(W), which scales the blocks by W.
  Tangent3 (*tangent_blocks3)(const Eigen::Matrix3d& F, const Eigen::Matrix3d& D,
                              const Lame& m) = nullptr;
  // A model whose energy, P and blocks of a 3 x 3 F first derive something
  // costly from F (Derived3, kinematics.h: corotated's rotation R of
  // F = R S, neo-Hookean's ln J) names that step derive3 and also gives
  // Psi, P and the blocks with its result passed in, so that a tetrahedron
  // evaluated several times at one state (an implicit method's line search
  // asks for the energy, then the force, then dF/dx at the point it
  // accepts) derives it once: tet_force.cc keeps each element's. Its P3
  // and tangent_blocks3 derive and call these (the same result bit for bit,
  // kept or not), and the tetrahedra take its energy from Psi3_derived
  // either way. nullptr: nothing to keep.
  void (*derive3)(const Eigen::Matrix3d& F, Derived3& d) = nullptr;
  double (*Psi3_derived)(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) = nullptr;
  Eigen::Matrix3d (*P3_derived)(const Eigen::Matrix3d& F, const Derived3& d,
                                const Lame& m) = nullptr;
  Tangent3 (*tangent_blocks3_derived)(const Eigen::Matrix3d& F, const Derived3& d,
                                      const Eigen::Matrix3d& D, const Lame& m) = nullptr;
  // Optional, with derive3: derive3 and tangent_blocks3_derived for
  // kLanes elements at once, in vector lanes (lanes.h), lane l's result bit
  // for bit the one-element function's for element l (the shared tests
  // check it). The tetrahedra call them kLanes elements at a time where a
  // model has them (a pointer may repeat, to fill the lanes). The blocks
  // stay in lanes: entry k of element l's 9 x 9 matrix (column-major, as
  // in a Tangent3) is lane l of K[k], K[k][l].
  void (*derive3_lanes)(const Eigen::Matrix3d* const (&F)[kLanes],
                        Derived3* const (&d)[kLanes]) = nullptr;
  // D and the Lame parameters come in lanes (D[3 r + c][l] is D(r, c) of
  // element l): they are constants of the elements, which the tetrahedra
  // arrange so once.
  void (*tangent_blocks3_derived_lanes)(const Eigen::Matrix3d* const (&F)[kLanes],
                                        const Derived3* const (&d)[kLanes],
                                        const Lanes (&D)[9], const Lanes& mu,
                                        const Lanes& lambda, Lanes (&K)[81]) = nullptr;
};

// The registered models, in registry order; nullptr for an unknown name.
const std::vector<const MaterialModel*>& material_models();
const MaterialModel* find_material_model(std::string_view name);
// "linear, corotated, ..." for messages.
std::string material_model_names();

// dPdF on vec(F) (column-major: entry (r, c) of F is r + d c), column by
// column from dP along each basis matrix E_rc: the reference every closed
// form is checked against.
Tangent dPdF(const MaterialModel& model, const Mat& F, const Lame& m);
// P of a 3 x 3 F: the model's fixed-size instance when it has one, else P.
Eigen::Matrix3d P3(const MaterialModel& model, const Eigen::Matrix3d& F, const Lame& m);
// The blocks A(d_i, d_j) of a 3 x 3 F (above): the model's closed form when
// it has one, else the contraction of dPdF.
Tangent3 tangent_blocks3(const MaterialModel& model, const Eigen::Matrix3d& F,
                         const Eigen::Matrix3d& D, const Lame& m);

}  // namespace springlab
