// Every registered material model (models/materials/), on every shape of F it
// is defined for (2 x 2 plane strain, 3 x 3 solid, 3 x 2 membrane): the
// properties docs/physics.md "Finite elements" states and the derivatives the solvers rely on,
// checked against closed forms and central differences.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "models/materials/kernels/kinematics.h"
#include "models/materials/material.h"
#include "models/materials/kernels/tangent3.h"
#include "models/materials/kernels/tet_kernel.h"
#include "registry_suite.h"

namespace springlab::test_materials {
namespace {

struct MaterialCase {
  const MaterialModel* model;
  int rows, cols;
};

std::vector<MaterialCase> cases() {
  std::vector<MaterialCase> out;
  for (const MaterialModel* m : material_models()) {
    out.push_back({m, 2, 2});
    out.push_back({m, 3, 3});
    if (m->membranes) out.push_back({m, 3, 2});
  }
  return out;
}

std::string case_name(const ::testing::TestParamInfo<MaterialCase>& info) {
  std::string name(info.param.model->name);
  std::replace(name.begin(), name.end(), '-', '_');
  return name + "_" + std::to_string(info.param.rows) + "x" + std::to_string(info.param.cols);
}

void PrintTo(const MaterialCase& c, std::ostream* os) {
  *os << c.model->name << ", " << c.rows << " x " << c.cols;
}

// The cases that meet `applies` (from the model's declared members and the
// shape of F), for a suite whose tests apply to those only; recorded for
// tests/test_registry_coverage.cc.
std::vector<MaterialCase> cases_where(const std::string& suite,
                                      bool (*applies)(const MaterialCase&)) {
  std::vector<MaterialCase> out;
  std::vector<std::string> names;
  for (const MaterialCase& c : cases()) {
    if (!applies(c)) continue;
    out.push_back(c);
    names.push_back(case_name({c, 0}));
  }
  testing::conditional_suites()[suite] = names;
  return out;
}

// Rubber-like: E = 1e5 Pa, nu = 0.4.
const Lame kLame = lame(1e5, 0.4);

class EveryMaterial : public ::testing::TestWithParam<MaterialCase> {
 protected:
  const MaterialModel& model() const { return *GetParam().model; }
  Mat identity() const { return Mat::Identity(GetParam().rows, GetParam().cols); }
  // A moderate random deformation with J > 0: I + 0.3 U(-1, 1).
  Mat deformed(std::mt19937& rng) const {
    std::uniform_real_distribution<double> u(-0.3, 0.3);
    for (;;) {
      Mat F = identity();
      for (Eigen::Index i = 0; i < F.size(); ++i) F.data()[i] += u(rng);
      if (volume(F).J > 0.3) return F;
    }
  }
  // A random rotation of the deformed space (d x d).
  Mat rotation(std::mt19937& rng) const {
    std::normal_distribution<double> n(0.0, 1.0);
    Mat A(GetParam().rows, GetParam().rows);
    for (Eigen::Index i = 0; i < A.size(); ++i) A.data()[i] = n(rng);
    Eigen::HouseholderQR<Mat> qr(A);
    Mat Q = qr.householderQ();
    if (Q.determinant() < 0.0) Q.col(0) *= -1.0;
    return Q;
  }
};

// The suites below apply to the cases their condition selects.
// A square F (2 x 2, 3 x 3): the linear model is not defined for membranes.
class EveryMaterialSquareF : public EveryMaterial {};
bool square(const MaterialCase& c) { return c.rows == c.cols; }
bool solid(const MaterialCase& c) { return c.rows == 3 && c.cols == 3; }
// 3 x 3: the tetrahedra's kernel (tet_kernel.h).
class EveryMaterialTetKernel : public EveryMaterial {};
// 3 x 3, with a kernel for kLanes elements at once.
class EveryMaterialLanes3 : public EveryMaterial {};
bool solid_lanes(const MaterialCase& c) {
  const TetKernel& kernel = *c.model->tet;
  return solid(c) && (kernel.derive_lanes != nullptr || kernel.blocks_lanes != nullptr);
}

// What the kernel keeps of F (nothing: zeros).
Derived3 derived(const TetKernel& kernel, const Eigen::Matrix3d& F) {
  Derived3 d;
  d.R.setZero();
  if (kernel.derive != nullptr) kernel.derive(F, d);
  return d;
}

TEST_P(EveryMaterial, RestIsStressFreeWithZeroEnergy) {
  EXPECT_NEAR(model().Psi(identity(), kLame), 0.0, 1e-9 * kLame.mu);
  EXPECT_LT(model().P(identity(), kLame).norm(), 1e-9 * kLame.mu);
}

TEST_P(EveryMaterial, StressIsTheGradientOfTheEnergy) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 5; ++trial) {
    const Mat F = deformed(rng);
    const Mat P = model().P(F, kLame);
    const double h = 1e-6;
    for (Eigen::Index i = 0; i < F.size(); ++i) {
      Mat Fp = F, Fm = F;
      Fp.data()[i] += h;
      Fm.data()[i] -= h;
      const double numeric = (model().Psi(Fp, kLame) - model().Psi(Fm, kLame)) / (2.0 * h);
      EXPECT_NEAR(P.data()[i], numeric, 1e-6 * (1.0 + std::abs(numeric)) + 1e-4)
          << "entry " << i << " trial " << trial;
    }
  }
}

TEST_P(EveryMaterial, TangentIsTheDerivativeOfTheStress) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    const Mat F = deformed(rng);
    const Tangent T = dPdF(model(), F, kLame);
    const double h = 1e-6;
    for (Eigen::Index i = 0; i < F.size(); ++i) {
      Mat Fp = F, Fm = F;
      Fp.data()[i] += h;
      Fm.data()[i] -= h;
      const Mat numeric = (model().P(Fp, kLame) - model().P(Fm, kLame)) / (2.0 * h);
      for (Eigen::Index j = 0; j < F.size(); ++j) {
        EXPECT_NEAR(T(j, i), numeric.data()[j], 1e-5 * (1.0 + std::abs(numeric.data()[j])))
            << "entry (" << j << ", " << i << ") trial " << trial;
      }
    }
    // A hyperelastic tangent is a Hessian: symmetric.
    EXPECT_LT((T - T.transpose()).norm(), 1e-9 * T.norm());
  }
}

// The tetrahedra's kernel of a 3 x 3 F, from what it keeps of F, is the
// plain model: its blocks (closed form where the model has one, A(d_i, d_j)
// for the rows of a random D) the contraction of the tangent assembled from
// dP, entry for entry, its P the plain P and its energy the plain energy,
// at random deformations and -- for every model defined there -- inverted
// ones (J < 0).
TEST_P(EveryMaterialTetKernel, KernelIsThePlainModel) {
  const TetKernel& kernel = *model().tet;
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> entry(-1.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    Mat F = deformed(rng);
    if (trial % 2 == 1 && model().finite_everywhere) F.col(0) *= -1.0;  // inverted
    Eigen::Matrix3d D;
    for (int k = 0; k < 9; ++k) D.data()[k] = entry(rng);
    const Eigen::Matrix3d F3 = F;
    const Derived3 d = derived(kernel, F3);
    const Tangent3 reference = tangent_blocks(Tangent3(dPdF(model(), F, kLame)), D);
    EXPECT_LT((kernel.blocks(F3, d, D, kLame) - reference).norm(), 1e-12 * reference.norm())
        << "trial " << trial << ", J " << volume(F).J;
    const Mat P = model().P(F, kLame);
    EXPECT_LT((kernel.P(F3, d, kLame) - Eigen::Matrix3d(P)).norm(), 1e-14 * P.norm())
        << "trial " << trial;
    const double psi = model().Psi(F, kLame);
    EXPECT_NEAR(kernel.Psi(F3, d, kLame), psi, 1e-14 * std::abs(psi)) << "trial " << trial;
  }
}

// A material of Psi, P and dP alone (here stvk's, without its closed-form
// blocks and fixed-size P): the kernel generated for it gives stvk's plain
// P and the contraction of the dPdF assembled from its dP, bit for bit,
// keeps nothing and has no lanes.
struct OnlyTheCore {
  static constexpr MaterialFacts facts = {.name = "stvk-core", .formula = "stvk's"};
  static const MaterialModel& stvk() { return *find_material_model("stvk"); }
  static double Psi(const Mat& F, const Lame& m) { return stvk().Psi(F, m); }
  static Mat P(const Mat& F, const Lame& m) { return stvk().P(F, m); }
  static Mat dP(const Mat& F, const Mat& dF, const Lame& m) { return stvk().dP(F, dF, m); }
};

TEST(Materials, KernelGeneratedFromPsiPAndDPAlone) {
  const MaterialModel core = tet_kernel::model<OnlyTheCore>(nullptr);
  const TetKernel& kernel = *core.tet;
  EXPECT_EQ(core.name, "stvk-core");
  EXPECT_EQ(kernel.derive, nullptr);
  EXPECT_EQ(kernel.derive_lanes, nullptr);
  EXPECT_EQ(kernel.blocks_lanes, nullptr);
  const MaterialModel& stvk = OnlyTheCore::stvk();
  std::mt19937 rng(37);
  std::uniform_real_distribution<double> entry(-0.3, 0.3);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity(), D;
    for (int k = 0; k < 9; ++k) {
      F.data()[k] += entry(rng);
      D.data()[k] = entry(rng);
    }
    const Derived3 d = derived(kernel, F);
    EXPECT_EQ(kernel.Psi(F, d, kLame), stvk.Psi(F, kLame));
    EXPECT_EQ(kernel.P(F, d, kLame), Eigen::Matrix3d(stvk.P(F, kLame)));
    const Tangent3 contracted = tangent_blocks(Tangent3(dPdF(stvk, F, kLame)), D);
    EXPECT_EQ(kernel.blocks(F, d, D, kLame), contracted) << "trial " << trial;
    // and stvk's closed form agrees with it to round-off
    const Tangent3 closed = stvk.tet->blocks(F, d, D, kLame);
    EXPECT_LT((closed - contracted).norm(), 1e-12 * contracted.norm());
    // (and is another computation: the kernel took the contraction)
    EXPECT_NE(closed, contracted);
  }
}

// A model that derives and gives its blocks for kLanes elements at once, in
// vector lanes (TetKernel::derive_lanes and blocks_lanes; lanes.h), gives
// in each lane what its
// one-element functions give for that element, bit for bit, whichever
// elements share the call: rotated and deformed ones (some turned by more
// than the series' range of the polar decomposition allows), inverted ones
// and strongly stretched ones side by side, each with its own D and
// Lame parameters.
TEST_P(EveryMaterialLanes3, LanesAreTheOneElementFunctionsBitForBit) {
  const TetKernel& m = *model().tet;
  // The blocks in lanes take what derive gives.
  ASSERT_NE(m.derive, nullptr);
  ASSERT_NE(m.derive_lanes, nullptr);
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> entry(-1.0, 1.0);
  std::uniform_int_distribution<int> kind(0, 3);
  for (int call = 0; call < 50; ++call) {
    std::array<Eigen::Matrix3d, kLanes> F, D;
    std::array<Lame, kLanes> lames;
    std::array<Derived3, kLanes> d;
    Lanes blocks[81], D_in[9], mu, lambda;
    const Eigen::Matrix3d* F_in[kLanes];
    Derived3* d_out[kLanes];
    const Derived3* d_in[kLanes];
    for (std::size_t l = 0; l < static_cast<std::size_t>(kLanes); ++l) {
      F[l] = Eigen::Matrix3d(rotation(rng)) * Eigen::Matrix3d(deformed(rng));
      const int k = kind(rng);
      if (k == 1 && model().finite_everywhere) F[l].col(0) *= -1.0;  // inverted
      if (k == 2) F[l].col(1) *= 3.0;                          // stretched
      for (int i = 0; i < 9; ++i) D[l].data()[i] = entry(rng);
      lames[l] = lame(1e5 * (1.0 + entry(rng) * entry(rng)), 0.3 + 0.1 * entry(rng));
      F_in[l] = &F[l];
      for (int i = 0; i < 9; ++i) D_in[i][l] = D[l](i / 3, i % 3);
      mu[l] = lames[l].mu;
      lambda[l] = lames[l].lambda;
      d_out[l] = &d[l];
      d_in[l] = &d[l];
      d[l].R.setZero();  // what a model derives nothing into compares equal
    }
    m.derive_lanes(F_in, d_out);
    for (std::size_t l = 0; l < static_cast<std::size_t>(kLanes); ++l) {
      Derived3 one;
      one.R.setZero();
      m.derive(F[l], one);
      EXPECT_EQ(d[l].R, one.R) << "call " << call << ", lane " << l;
      EXPECT_EQ(d[l].log_J, one.log_J) << "call " << call << ", lane " << l;
    }
    if (m.blocks_lanes == nullptr) continue;
    m.blocks_lanes(F_in, d_in, D_in, mu, lambda, blocks);
    for (std::size_t l = 0; l < static_cast<std::size_t>(kLanes); ++l) {
      Tangent3 in_lane;
      for (int k = 0; k < 81; ++k) in_lane.data()[k] = blocks[k][l];
      EXPECT_EQ(in_lane, m.blocks(F[l], d[l], D[l], lames[l]))
          << "call " << call << ", lane " << l;
    }
  }
}

TEST_P(EveryMaterial, EnergyIsInvariantUnderRotationButLinearIsNot) {
  std::mt19937 rng(3);
  const Mat F = deformed(rng);
  const Mat R = rotation(rng);
  const double psi = model().Psi(F, kLame), rotated = model().Psi(R * F, kLame);
  if (model().name == "linear") {
    // A rigid rotation by 0.5 rad stores energy in the linear model.
    Mat Q = identity();
    Q.topLeftCorner(2, 2) << std::cos(0.5), -std::sin(0.5), std::sin(0.5), std::cos(0.5);
    EXPECT_GT(model().Psi(Q, kLame), 1e-3 * kLame.mu);
  } else {
    EXPECT_NEAR(rotated, psi, 1e-9 * (1.0 + std::abs(psi)));
  }
}

// Small strain: every model agrees with linear elasticity to first order,
// so their stresses at F = I + eps G differ by O(eps^2).
TEST_P(EveryMaterialSquareF, SmallStrainStressIsLinearElasticity) {
  const Mat G = (Mat(GetParam().rows, GetParam().cols) << Mat::Random(GetParam().rows,
                                                                      GetParam().cols))
                    .finished();
  const Mat sym = 0.5 * (G + G.transpose());  // a pure strain (no rotation)
  const MaterialModel& linear = *find_material_model("linear");
  for (double eps : {1e-3, 1e-4}) {
    const Mat F = identity() + eps * sym;
    const double difference = (model().P(F, kLame) - linear.P(F, kLame)).norm();
    const double size = linear.P(F, kLame).norm();
    EXPECT_LT(difference, 20.0 * eps * size) << "eps " << eps;
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryMaterial, ::testing::ValuesIn(cases()), case_name);
INSTANTIATE_TEST_SUITE_P(Registry, EveryMaterialSquareF,
                         ::testing::ValuesIn(cases_where("Registry/EveryMaterialSquareF", square)),
                         case_name);
INSTANTIATE_TEST_SUITE_P(Registry, EveryMaterialTetKernel,
                         ::testing::ValuesIn(cases_where("Registry/EveryMaterialTetKernel", solid)),
                         case_name);
INSTANTIATE_TEST_SUITE_P(Registry, EveryMaterialLanes3,
                         ::testing::ValuesIn(cases_where("Registry/EveryMaterialLanes3",
                                                         solid_lanes)),
                         case_name);

TEST(Materials, LameParametersFromYoungAndPoisson) {
  const Lame m = lame(2.6e5, 0.3);
  EXPECT_DOUBLE_EQ(m.mu, 1e5);                        // E / (2 (1 + nu))
  EXPECT_NEAR(m.lambda, 2.6e5 * 0.3 / (1.3 * 0.4), 1e-9);  // E nu / ((1 + nu)(1 - 2 nu))
}

TEST(Materials, NeoHookeanHasNoEnergyWhereTheElementIsInverted) {
  const MaterialModel& nh = *find_material_model("neo-hookean");
  Mat F = Mat::Identity(3, 3);
  F(2, 2) = -0.5;
  EXPECT_EQ(nh.Psi(F, kLame), std::numeric_limits<double>::infinity());
  EXPECT_TRUE(nh.P(F, kLame).array().isNaN().all());
  // Stable neo-Hookean is finite there and pushes back (energy falls toward
  // J > 0).
  const MaterialModel& snh = *find_material_model("stable-neo-hookean");
  EXPECT_TRUE(std::isfinite(snh.Psi(F, kLame)));
  EXPECT_LT(snh.P(F, kLame)(2, 2), 0.0);
}

// polar3 (the Newton-Schulz iteration near a rotation, Higham's Newton
// iteration elsewhere where det F > 0, the SVD where det F <= 0) gives the
// proper rotation U V^T of the SVD, sign-flipped where det F < 0, and
// F = R S with S symmetric: near rest, turned and deformed by up to about
// 30 % (all but one of these in the Newton-Schulz range, |F^T F - I|_F < 0.6),
// strongly stretched (condition 1e6), nearly flat, and inverted.
TEST(Materials, PolarDecompositionIsTheSvdsRotation) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Matrix3d F;
    for (int k = 0; k < 9; ++k) F.data()[k] = n(rng);
    if (trial % 5 == 0) F = Eigen::Matrix3d::Identity() + 1e-3 * F;  // near rest
    if (trial % 5 == 1) F.col(0) *= 1e6;                            // condition ~1e6
    if (trial % 5 == 2) F.col(2) = F.col(0) + F.col(1) + 1e-7 * F.col(2);  // nearly flat
    if (trial % 5 == 4) {  // turned by up to 5 pi / 6, deformed by up to about 30 %
      const Eigen::Vector3d axis = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
      const double angle = 3.14159 * (trial % 7) / 6.0;
      F = Eigen::AngleAxisd(angle, axis).toRotationMatrix() *
          (Eigen::Matrix3d::Identity() + 0.09 * F);
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d U = svd.matrixU();
    if ((U * svd.matrixV().transpose()).determinant() < 0.0) U.col(2) *= -1.0;
    const Eigen::Matrix3d expected = U * svd.matrixV().transpose();
    const Polar3 p = polar3(F);
    // Both are exact to rounding times R's sensitivity, ~ sigma_max / sigma_min.
    const double tolerance = trial % 5 == 1 ? 1e-11 : 1e-13;
    EXPECT_LT((p.R - expected).norm(), tolerance)
        << "trial " << trial << ", det " << F.determinant();
    EXPECT_LT((p.R.transpose() * p.R - Eigen::Matrix3d::Identity()).norm(), 1e-14) << trial;
    EXPECT_NEAR(p.R.determinant(), 1.0, 1e-14) << trial;
    EXPECT_LT((p.R * p.S - F).norm(), 1e-14 * F.norm()) << trial;
    EXPECT_EQ(p.S, p.S.transpose()) << trial;
  }
}

// rotation3_lanes finds the rotation of kLanes matrices at once, in vector
// lanes: each lane's R is polar3's bit for bit, whichever matrices share
// the call: near rest and deformed by up to 30 % (the series in lanes,
// taking different numbers of steps side by side), and, in the same calls,
// matrices outside the series' range (strongly stretched, inverted, flat)
// that polar3 hands to Higham's iteration or the SVD.
TEST(Materials, RotationInLanesIsPolar3sBitForBit) {
  std::mt19937 rng(17);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_int_distribution<int> kind(0, 5);
  for (int call = 0; call < 100; ++call) {
    std::array<Eigen::Matrix3d, kLanes> F, R;
    const Eigen::Matrix3d* in[kLanes];
    Eigen::Matrix3d* out[kLanes];
    for (int l = 0; l < kLanes; ++l) {
      Eigen::Matrix3d& f = F[static_cast<std::size_t>(l)];
      for (int k = 0; k < 9; ++k) f.data()[k] = n(rng);
      const Eigen::Matrix3d turn =
          Eigen::AngleAxisd(3.0 * n(rng), Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized())
              .toRotationMatrix();
      switch (kind(rng)) {
        case 0: f = turn * (Eigen::Matrix3d::Identity() + 1e-4 * f); break;  // near rest
        case 1: case 2: f = turn * (Eigen::Matrix3d::Identity() + 0.09 * f); break;
        case 3: f.col(0) *= 10.0; break;                                     // stretched
        case 4: f = turn * (Eigen::Matrix3d::Identity() + 0.05 * f); f.col(2) *= -1.0; break;
        default: f.col(2) = f.col(0) + 1e-9 * f.col(2); break;               // flat
      }
      in[l] = &f;
      out[l] = &R[static_cast<std::size_t>(l)];
    }
    rotation3_lanes(in, out);
    for (int l = 0; l < kLanes; ++l) {
      EXPECT_EQ(*out[l], polar3(*in[l]).R) << "call " << call << ", lane " << l;
    }
  }
}

// nearest_unit_volume (projective dynamics' volume constraint): T has
// J = 1, and it is the nearest such matrix: F - T is normal to the set at
// T, i.e. parallel to dJ/dF at T (Lagrange), for 3 x 3, 2 x 2 and 3 x 2 F
// stretched or compressed by up to 40 %; a matrix already on the set is its
// own projection, and T is no farther from F than the uniformly scaled
// F / J^(1/k), another point of the set.
TEST(Materials, NearestUnitVolumeIsTheNearestMatrixOfUnitJ) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const auto& [d, k] : std::vector<std::pair<int, int>>{{3, 3}, {2, 2}, {3, 2}}) {
    for (int trial = 0; trial < 50; ++trial) {
      Mat F = Mat::Identity(d, k);
      for (int r = 0; r < d; ++r)
        for (int c = 0; c < k; ++c) F(r, c) += 0.4 * u(rng);
      if (!(volume(F).J > 0.05)) continue;
      const Mat T = nearest_unit_volume(F);
      const Volume v = volume(T);
      EXPECT_NEAR(v.J, 1.0, 1e-12) << d << "x" << k << " trial " << trial;
      const Mat N = F - T;
      const double m = contract(N, v.g) / contract(v.g, v.g);
      EXPECT_LT((N - m * v.g).norm(), 1e-10 * std::max(1.0, N.norm()))
          << d << "x" << k << " trial " << trial << ", J(F) " << volume(F).J;
      EXPECT_LT((nearest_unit_volume(T) - T).norm(), 1e-12) << d << "x" << k;
      const Mat scaled = F / std::pow(volume(F).J, 1.0 / k);
      EXPECT_LE((F - T).norm(), (F - scaled).norm() + 1e-14) << d << "x" << k;
    }
  }
}

}  // namespace
}  // namespace springlab::test_materials
