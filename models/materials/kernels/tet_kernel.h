// The tetrahedra's kernel of a material (tet_force.cc), generated from its
// class (material.h): what a tetrahedron asks of its material at a 3 x 3 F,
// and the registration that makes a MaterialModel of the class.
//
// A class gives Psi, P and dP (required) and, where the kernel cannot
// derive them fast, for 3 x 3 F only (optional; the shared tests check each
// against the plain formulas):
//   - P as a template on the matrix type: P<Eigen::Matrix3d> is the
//     tetrahedra's P (else P of a dynamic-size copy of F);
//   - blocks(F, D, m): the tangent contracted with the rows a, b of D,
//     A(a, b)_rs = sum_cd a_c (dP_rc / dF_sd) b_d, in closed form
//     (tangent3.h; else the contraction of the dPdF assembled from 9 dP);
//   - `static constexpr Keeps keeps`: the costly quantity of F that Psi, P
//     and blocks share (the rotation R of F = R S, ln J), with
//     Psi(F, d, m), P(F, d, m) and blocks(F, d, D, m) taking it in d
//     (Derived3, kinematics.h). The tetrahedra keep each element's between
//     calls at one state (an implicit method's line search asks for the
//     energy, then the force, then dF/dx at the point it accepts) and
//     derive the rotation for kLanes elements at once (rotation3_lanes);
//   - blocks written once on arrays as a template on the number type T
//     (lanes.h), blocks(F, R, log_J, D, mu, lambda, store) with what it
//     keeps of F in R (row-major) or log_J: the kernel runs it with
//     T = double for one element and with T = Lanes for kLanes elements at
//     once, bit for bit the same.
#pragma once

#include <cmath>
#include <concepts>
#include <limits>

#include "models/materials/kernels/kinematics.h"  // Derived3, polar3, volume
#include "models/materials/kernels/lanes.h"
#include "models/materials/material.h"
#include "models/materials/kernels/tangent3.h"    // tangent_blocks

namespace springlab {

// What a material's Psi, P and blocks of a 3 x 3 F share (Derived3).
enum class Keeps { nothing, rotation, log_J };

struct TetKernel {
  // Fills d with what the material keeps (nullptr: it keeps nothing), for
  // one element and for kLanes at once (nullptr: one by one; the pointers
  // may repeat, to fill the lanes).
  void (*derive)(const Eigen::Matrix3d& F, Derived3& d) = nullptr;
  void (*derive_lanes)(const Eigen::Matrix3d* const (&F)[kLanes],
                       Derived3* const (&d)[kLanes]) = nullptr;
  // Psi, P and the blocks A(d_i, d_j) of the rows of D, given derive's d.
  double (*Psi)(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) = nullptr;
  Eigen::Matrix3d (*P)(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) = nullptr;
  Tangent3 (*blocks)(const Eigen::Matrix3d& F, const Derived3& d, const Eigen::Matrix3d& D,
                     const Lame& m) = nullptr;
  // The blocks of kLanes elements at once (nullptr: one by one). D and the
  // Lame parameters come in lanes (D[3 r + c][l] is D(r, c) of element l),
  // constants the tetrahedra arrange once; entry k of element l's 9 x 9
  // matrix (column-major, as in a Tangent3) is K[k][l].
  void (*blocks_lanes)(const Eigen::Matrix3d* const (&F)[kLanes],
                       const Derived3* const (&d)[kLanes], const Lanes (&D)[9], const Lanes& mu,
                       const Lanes& lambda, Lanes (&K)[81]) = nullptr;
};

namespace tet_kernel {

inline void derive_rotation(const Eigen::Matrix3d& F, Derived3& d) { d.R = polar3(F).R; }
inline void derive_rotation_lanes(const Eigen::Matrix3d* const (&F)[kLanes],
                                  Derived3* const (&d)[kLanes]) {
  Eigen::Matrix3d* R[kLanes];
  for (int l = 0; l < kLanes; ++l) R[l] = &d[l]->R;
  rotation3_lanes(F, R);
}
// ln J, NaN where J <= 0 (where a material with ln J has no energy).
inline void derive_log_J(const Eigen::Matrix3d& F, Derived3& d) {
  const double J = volume(F).J;
  d.log_J = J > 0.0 ? std::log(J) : std::numeric_limits<double>::quiet_NaN();
}

template <class Model>
constexpr Keeps keeps() {
  if constexpr (requires { Model::keeps; }) {
    return Model::keeps;
  } else {
    return Keeps::nothing;
  }
}

struct DiscardEntry {
  void operator()(int, const double&) const {}
};
template <class Model>
concept BlocksOnArrays = requires(const double (&a)[9], const double& s) {
  Model::blocks(a, a, s, a, s, s, DiscardEntry{});
};
template <class Model>
concept ClosedFormBlocks = requires(const Eigen::Matrix3d& F, const Lame& m) {
  { Model::blocks(F, F, m) } -> std::same_as<Tangent3>;
};

template <class Model>
double Psi(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) {
  if constexpr (keeps<Model>() == Keeps::nothing) {
    return Model::Psi(Mat(F), m);
  } else {
    return Model::Psi(F, d, m);
  }
}

template <class Model>
Eigen::Matrix3d P(const Eigen::Matrix3d& F, const Derived3& d, const Lame& m) {
  if constexpr (keeps<Model>() == Keeps::nothing) {
    return Eigen::Matrix3d(Model::P(F, m));  // P<Matrix3d> where P is a template
  } else {
    return Model::P(F, d, m);
  }
}

template <class Model>
Tangent3 blocks(const Eigen::Matrix3d& F, const Derived3& d, const Eigen::Matrix3d& D,
                const Lame& m) {
  if constexpr (BlocksOnArrays<Model>) {
    double f[9], R[9], dd[9];
    for (int k = 0; k < 9; ++k) {
      f[k] = F(k / 3, k % 3);
      if constexpr (keeps<Model>() == Keeps::rotation) R[k] = d.R(k / 3, k % 3);
      dd[k] = D(k / 3, k % 3);
    }
    Tangent3 K;
    Model::blocks(f, R, d.log_J, dd, m.mu, m.lambda,
                  [&](int k, const double& v) { K.data()[k] = v; });
    return K;
  } else if constexpr (keeps<Model>() != Keeps::nothing) {
    return Model::blocks(F, d, D, m);
  } else if constexpr (ClosedFormBlocks<Model>) {
    return Model::blocks(F, D, m);
  } else {
    Tangent T(9, 9);  // dPdF column by column from dP (material_registry.cc)
    for (int c = 0; c < 3; ++c) {
      for (int r = 0; r < 3; ++r) {
        Mat E = Mat::Zero(3, 3);
        E(r, c) = 1.0;
        const Mat dP = Model::dP(Mat(F), E, m);
        for (int k = 0; k < 9; ++k) T(k, r + 3 * c) = dP(k % 3, k / 3);
      }
    }
    return tangent_blocks(Tangent3(T), D);
  }
}

// The blocks of kLanes elements, where the class writes them on arrays.
template <class Model>
SPRINGLAB_LANES_INLINE void blocks_lanes(const Eigen::Matrix3d* const (&F)[kLanes],
                                         const Derived3* const (&d)[kLanes], const Lanes (&D)[9],
                                         const Lanes& mu, const Lanes& lambda, Lanes (&K)[81]) {
  if constexpr (BlocksOnArrays<Model>) {
    Lanes f[9], R[9];
    Lanes log_J = {};  // (read only by a material that keeps ln J)
    for (int l = 0; l < kLanes; ++l) {
      for (int k = 0; k < 9; ++k) {
        f[k][l] = (*F[l])(k / 3, k % 3);
        if constexpr (keeps<Model>() == Keeps::rotation) R[k][l] = d[l]->R(k / 3, k % 3);
      }
      if constexpr (keeps<Model>() == Keeps::log_J) log_J[l] = d[l]->log_J;
    }
    Model::blocks(f, R, log_J, D, mu, lambda, [&](int k, const Lanes& v) { K[k] = v; });
  }
}

template <class Model>
MaterialModel model(decltype(TetKernel::blocks_lanes) blocks_lanes_clones) {
  static const TetKernel kernel = {
      .derive = keeps<Model>() == Keeps::rotation ? derive_rotation
                : keeps<Model>() == Keeps::log_J  ? derive_log_J
                                                  : nullptr,
      .derive_lanes = keeps<Model>() == Keeps::rotation ? derive_rotation_lanes : nullptr,
      .Psi = tet_kernel::Psi<Model>,
      .P = tet_kernel::P<Model>,
      .blocks = tet_kernel::blocks<Model>,
      .blocks_lanes = BlocksOnArrays<Model> ? blocks_lanes_clones : nullptr,
  };
  MaterialModel out;
  static_cast<MaterialFacts&>(out) = Model::facts;
  out.Psi = [](const Mat& F, const Lame& m) -> double { return Model::Psi(F, m); };
  out.P = [](const Mat& F, const Lame& m) -> Mat { return Model::P(F, m); };
  out.dP = [](const Mat& F, const Mat& dF, const Lame& m) -> Mat { return Model::dP(F, dF, m); };
  out.tet = &kernel;
  return out;
}

}  // namespace tet_kernel

// Registers the class Model as `const MaterialModel& NAME_material()`, the
// function named by its line in material_registry.cc. The blocks in lanes
// are compiled here, once per target (SPRINGLAB_LANES_CLONES, lanes.h: Clang
// clones no function template); where the class writes no blocks on arrays
// the function is empty and the kernel has none.
#define SPRINGLAB_MATERIAL(Model, NAME)                                                        \
  namespace {                                                                                  \
  SPRINGLAB_LANES_CLONES void NAME##_blocks_lanes(                                             \
      const Eigen::Matrix3d* const (&F)[kLanes], const Derived3* const (&d)[kLanes],           \
      const Lanes (&D)[9], const Lanes& mu, const Lanes& lambda, Lanes (&K)[81]) {             \
    tet_kernel::blocks_lanes<Model>(F, d, D, mu, lambda, K);                                   \
  }                                                                                            \
  }                                                                                            \
  const MaterialModel& NAME##_material() {                                                     \
    static const MaterialModel model = tet_kernel::model<Model>(NAME##_blocks_lanes);          \
    return model;                                                                              \
  }

}  // namespace springlab
