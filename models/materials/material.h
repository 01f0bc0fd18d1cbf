// Hyperelastic materials (docs/physics.md "Finite elements"; the lecture's "generalized springs"):
// an energy density Psi(F) of the deformation gradient F = Ds Dm^-1, its first
// Piola-Kirchhoff stress P = dPsi/dF, and the derivative of P.
//
// F is d x k: square for solids (2 x 2 plane strain, 3 x 3 tetrahedra) and
// 3 x 2 for membranes (triangles in 3-D: in-plane stretch and shear only).
// Every formula is written for any of these shapes, with C = F^T F
// (k x k), I_C = tr C and J the element's area or volume ratio
// (kinematics.h).
//
// A material is one class in one file (as in HOBAK, Kim and Eberle,
// "Dynamic Deformables", SIGGRAPH course 2022: one class per energy with
// Psi, PK1 and Hessian), static members only:
//
//   struct StVK {
//     static constexpr MaterialFacts facts = {.name = "stvk", .formula = "..."};
//     static double Psi(const Mat& F, const Lame& m);              // Psi(F)
//     static Mat P(const Mat& F, const Lame& m);                   // P = dPsi/dF
//     static Mat dP(const Mat& F, const Mat& dF, const Lame& m);  // dP = (dP/dF)[dF]
//   };
//   SPRINGLAB_MATERIAL(StVK, stvk)  // tet_kernel.h: registers it as stvk_material()
//
// and one line in material_registry.cc. dP is the differential of the P
// formula, in closed form; dPdF (below) assembles the tangent from it, so
// one formula serves every shape. The tetrahedra's kernel (tet_kernel.h)
// is generated from these three; a class may add, for 3 x 3 F only, what
// the kernel cannot derive fast (tet_kernel.h lists the optional members):
// P as a template on the matrix type (a fixed-size instance), its tangent
// contracted with two rest-shape gradients in closed form (`blocks`,
// tangent3.h), and which costly quantity of F its Psi, P and blocks share
// (`keeps`: the rotation of F = R S, or ln J), which the tetrahedra keep per
// element and derive in vector lanes.
#pragma once

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

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

// What a material states about itself, beside its formulas.
struct MaterialFacts {
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
};

struct TetKernel;  // tet_kernel.h

// A registered material as the rest of the code sees it: its facts, the
// plain Psi, P and dP of any shape of F (fem_force.cc, the reference), and
// the tetrahedra's kernel, all generated from its class (tet_kernel.h).
struct MaterialModel : MaterialFacts {
  double (*Psi)(const Mat& F, const Lame& m) = nullptr;  // +infinity where undefined
  Mat (*P)(const Mat& F, const Lame& m) = nullptr;
  Mat (*dP)(const Mat& F, const Mat& dF, const Lame& m) = nullptr;
  const TetKernel* tet = nullptr;  // 3 x 3 F: tet_force.cc
};

// The registered models, in registry order; nullptr for an unknown name.
std::vector<const MaterialModel*> material_models();
const MaterialModel* find_material_model(std::string_view name);
// "linear, corotated, ..." for messages.
std::string material_model_names();

// dPdF on vec(F) (column-major: entry (r, c) of F is r + d c), column by
// column from dP along each basis matrix E_rc: the reference every closed
// form is checked against.
Tangent dPdF(const MaterialModel& model, const Mat& F, const Lame& m);

}  // namespace springlab
