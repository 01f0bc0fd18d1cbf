#include "models/fluids/fluid_pressure_hessian.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace springlab {
namespace {

// A, A' per particle, G per pair, R_jj per particle and each particle's
// neighbours (partner, pair) in CSR form; and, for the column assembly,
// R_j of each particle's members ({j}, then its neighbours in CSR order):
// j's start at (start[j] + j) D.
template <int D>
void prepare(const SphParticles& fluid, PressureHessianScratch& s) {
  const int n = fluid.size();
  const auto& pairs = fluid.pairs();
  const CubicSpline& w = fluid.kernel();
  const std::size_t un = static_cast<std::size_t>(n);
  s.a.resize(un);
  s.a_slope.resize(un);
  for (std::size_t j = 0; j < un; ++j) {
    const double rho = fluid.density()[j];
    s.a[j] = fluid.eos().a(rho);
    s.a_slope[j] = fluid.eos().a_slope(rho);
  }
  s.self.assign(un * D, 0.0);
  s.g.resize(pairs.size() * D);
  s.start.assign(un + 1, 0);
  for (const auto& [p, q] : pairs) {
    ++s.start[static_cast<std::size_t>(p + 1)];
    ++s.start[static_cast<std::size_t>(q + 1)];
  }
  for (std::size_t j = 0; j < un; ++j) s.start[j + 1] += s.start[j];
  s.partner.resize(static_cast<std::size_t>(s.start.back()));
  s.via.resize(s.partner.size());
  // (rank serves as the fill cursor here; the column assembly resets it.)
  s.rank.assign(s.start.begin(), s.start.end() - 1);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const auto [p, q] = pairs[k];
    const double so = w.slope_over_r(fluid.distance(k));
    const double* d = fluid.separation(k);
    for (int r = 0; r < D; ++r) {
      s.g[k * D + r] = so * d[r];  // G_pq
      s.self[static_cast<std::size_t>(p * D + r)] += fluid.mass(q) * s.g[k * D + r];
      s.self[static_cast<std::size_t>(q * D + r)] -= fluid.mass(p) * s.g[k * D + r];
    }
    const int ep = s.rank[static_cast<std::size_t>(p)]++;
    const int eq = s.rank[static_cast<std::size_t>(q)]++;
    s.partner[static_cast<std::size_t>(ep)] = q;
    s.via[static_cast<std::size_t>(ep)] = static_cast<int>(k);
    s.partner[static_cast<std::size_t>(eq)] = p;
    s.via[static_cast<std::size_t>(eq)] = static_cast<int>(k);
  }
}

// prepare() once per update of `fluid`: kept while its generation holds.
template <int D>
void prepare_once(const SphParticles& fluid, PressureHessianScratch& s) {
  if (s.fluid == &fluid && s.generation == fluid.generation()) return;
  prepare<D>(fluid, s);
  s.fluid = &fluid;
  s.generation = fluid.generation();
  s.pair_k_definite = -1;
}

// R_j,other = m_other G_other,j = -m_other G_j,other, from pair k (g[k] is
// G_first,second).
template <int D>
void neighbour_gradient(const SphParticles& fluid, const PressureHessianScratch& s, int other,
                        std::size_t k, double* out) {
  const double sign = fluid.pairs()[k].first == other ? 1.0 : -1.0;
  for (int r = 0; r < D; ++r) out[r] = sign * fluid.mass(other) * s.g[k * D + r];
}

// K = coefficient H of pair k (the kernel's Hessian, clamped when
// `definite`), row-major.
template <int D>
void pair_block(const SphParticles& fluid, std::size_t k, double coefficient, bool definite,
                double (&K)[D][D]) {
  const CubicSpline& w = fluid.kernel();
  const double r = fluid.distance(k);
  double across = w.slope_over_r(r), along = r > 0.0 ? w.curvature(r) : across;
  if (definite) {
    across = std::max(across, 0.0);
    along = std::max(along, 0.0);
  }
  double u[D];
  const double* d = fluid.separation(k);
  for (int i = 0; i < D; ++i) u[i] = r > 0.0 ? d[i] / r : 0.0;
  for (int i = 0; i < D; ++i) {
    for (int j = 0; j < D; ++j) {
      K[i][j] = coefficient * ((i == j ? across : 0.0) + (along - across) * u[i] * u[j]);
    }
  }
}

template <int D>
double pair_coefficient(const SphParticles& fluid, const PressureHessianScratch& s, int p, int q) {
  return fluid.mass(p) * fluid.mass(q) *
         (s.a[static_cast<std::size_t>(p)] + s.a[static_cast<std::size_t>(q)]);
}

}  // namespace

template <int D>
void add_pressure_stiffness(const SphParticles& fluid, int free_particles,
                            const SparseMatrix& pattern, bool definite, double* values,
                            PressureHessianScratch& s) {
  prepare_once<D>(fluid, s);
  const int n = fluid.size();
  const std::size_t un = static_cast<std::size_t>(n);
  // R_j of each particle's members: j itself, then its neighbours.
  s.members.resize((un + s.partner.size()) * D);
  for (int j = 0; j < n; ++j) {
    const std::size_t uj = static_cast<std::size_t>(j);
    double* out = &s.members[(static_cast<std::size_t>(s.start[uj]) + uj) * D];
    for (int r = 0; r < D; ++r) out[r] = s.self[uj * D + static_cast<std::size_t>(r)];
    for (int e = s.start[uj]; e < s.start[uj + 1]; ++e) {
      out += D;
      neighbour_gradient<D>(fluid, s, s.partner[static_cast<std::size_t>(e)],
                            static_cast<std::size_t>(s.via[static_cast<std::size_t>(e)]), out);
    }
  }
  const int* outer = pattern.outerIndexPtr();
  const int* inner = pattern.innerIndexPtr();
  // Indexed by the pattern's block rows: every free particle's, and beyond
  // them other unknowns' (a body's), which a fluid particle's column can
  // hold where another term couples them.
  s.rank.assign(static_cast<std::size_t>((pattern.rows() + D - 1) / D), -1);
  auto slot = [&](int row_particle) {
    const int r = s.rank[static_cast<std::size_t>(row_particle)];
    if (r < 0) throw std::logic_error("fluid: a Jacobian block is not in the pattern");
    return r;
  };
  for (int k = 0; k < n; ++k) {
    const int pk = fluid.index(k);
    if (pk >= free_particles) continue;
    const std::size_t uk = static_cast<std::size_t>(k);
    // Where each row particle's block sits in block column pk (the same
    // place in each of its D columns).
    const int first = outer[pk * D], last = outer[pk * D + 1];
    for (int i = first; i < last; i += D) {
      if (inner[i] % D != 0) throw std::logic_error("fluid: the pattern is not of whole blocks");
      s.rank[static_cast<std::size_t>(inner[i] / D)] = i - first;
    }
    double* column[D];
    for (int c = 0; c < D; ++c) column[c] = values + outer[pk * D + c];
    // block (row, pk) += scale u v^T.
    auto add_outer = [&](int row, const double* u, const double* v, double scale) {
      const int at = slot(row);
      for (int c = 0; c < D; ++c) {
        const double vc = scale * v[c];
        for (int r = 0; r < D; ++r) column[c][at + r] += vc * u[r];
      }
    };
    auto add_block = [&](int row, const double (&K)[D][D], double scale) {
      const int at = slot(row);
      for (int c = 0; c < D; ++c) {
        for (int r = 0; r < D; ++r) column[c][at + r] += scale * K[r][c];
      }
    };
    // Pair terms of k's pairs: (k, k) -K, (b, k) +K.
    for (int e = s.start[uk]; e < s.start[uk + 1]; ++e) {
      const int b = s.partner[static_cast<std::size_t>(e)];
      const double coefficient = pair_coefficient<D>(fluid, s, k, b);
      if (coefficient == 0.0) continue;
      double K[D][D];
      pair_block<D>(fluid, static_cast<std::size_t>(s.via[static_cast<std::size_t>(e)]), coefficient,
                    definite, K);
      add_block(pk, K, -1.0);
      const int pb = fluid.index(b);
      if (pb < free_particles) add_block(pb, K, 1.0);
    }
    // Rank-one terms: block (a, k) -= m_j A'_j R_ja R_jk^T for the j with
    // R_jk != 0 (k and its neighbours) and a in j's members.
    auto rank_one = [&](int j, const double* r_jk) {
      const std::size_t uj = static_cast<std::size_t>(j);
      const double weight = fluid.mass(j) * s.a_slope[uj];
      if (weight == 0.0) return;
      const double* r_j = &s.members[(static_cast<std::size_t>(s.start[uj]) + uj) * D];
      if (fluid.index(j) < free_particles) add_outer(fluid.index(j), r_j, r_jk, -weight);
      for (int e = s.start[uj]; e < s.start[uj + 1]; ++e) {
        r_j += D;
        const int pa = fluid.index(s.partner[static_cast<std::size_t>(e)]);
        if (pa < free_particles) add_outer(pa, r_j, r_jk, -weight);
      }
    };
    rank_one(k, &s.self[uk * D]);
    for (int e = s.start[uk]; e < s.start[uk + 1]; ++e) {
      // R_jk = m_k G_kj for the neighbour j.
      double r_jk[D];
      neighbour_gradient<D>(fluid, s, k, static_cast<std::size_t>(s.via[static_cast<std::size_t>(e)]),
                            r_jk);
      rank_one(s.partner[static_cast<std::size_t>(e)], r_jk);
    }
    for (int i = first; i < last; i += D) s.rank[static_cast<std::size_t>(inner[i] / D)] = -1;
  }
}

template <int D>
void add_pressure_stiffness_product(const SphParticles& fluid, int free_particles, bool definite,
                                    const double* p, double* out, PressureHessianScratch& s) {
  prepare_once<D>(fluid, s);
  const int n = fluid.size();
  const std::size_t un = static_cast<std::size_t>(n);
  const auto& pairs = fluid.pairs();
  // The pair blocks K_ab, once per update and kind of matrix.
  if (s.pair_k_definite != static_cast<int>(definite)) {
    s.pair_k.resize(pairs.size() * D * D);
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      double K[D][D];
      pair_block<D>(fluid, k, pair_coefficient<D>(fluid, s, pairs[k].first, pairs[k].second),
                    definite, K);
      for (int r = 0; r < D; ++r) {
        for (int c = 0; c < D; ++c) s.pair_k[(k * D + r) * D + c] = K[r][c];
      }
    }
    s.pair_k_definite = static_cast<int>(definite);
  }
  // p_a, or nullptr where a is fixed (its p is 0).
  auto p_of = [&](int a) -> const double* {
    const int i = fluid.index(a);
    return i < free_particles ? p + static_cast<std::size_t>(i) * D : nullptr;
  };
  auto dot = [](const double* u, const double* v) {
    double sum = 0.0;
    for (int r = 0; r < D; ++r) sum += u[r] * v[r];
    return sum;
  };
  // c_j = m_j A'_j s_j, s_j = R_jj . p_j + sum over j's neighbours k of R_jk . p_k.
  s.c.assign(un, 0.0);
  for (int j = 0; j < n; ++j) {
    const std::size_t uj = static_cast<std::size_t>(j);
    const double weight = fluid.mass(j) * s.a_slope[uj];
    if (weight == 0.0) continue;
    double sj = 0.0;
    if (const double* pj = p_of(j)) sj += dot(&s.self[uj * D], pj);
    for (int e = s.start[uj]; e < s.start[uj + 1]; ++e) {
      const int k = s.partner[static_cast<std::size_t>(e)];
      const double* pk = p_of(k);
      if (pk == nullptr) continue;
      double r_jk[D];
      neighbour_gradient<D>(fluid, s, k, static_cast<std::size_t>(s.via[static_cast<std::size_t>(e)]),
                            r_jk);
      sj += dot(r_jk, pk);
    }
    s.c[uj] = weight * sj;
  }
  // Rank-one terms: out_a -= sum over j in {a} and a's neighbours of c_j R_ja.
  for (int a = 0; a < n; ++a) {
    const int i = fluid.index(a);
    if (i >= free_particles) continue;
    const std::size_t ua = static_cast<std::size_t>(a);
    double* oa = out + static_cast<std::size_t>(i) * D;
    for (int r = 0; r < D; ++r) oa[r] -= s.c[ua] * s.self[ua * D + static_cast<std::size_t>(r)];
    for (int e = s.start[ua]; e < s.start[ua + 1]; ++e) {
      const double cj = s.c[static_cast<std::size_t>(s.partner[static_cast<std::size_t>(e)])];
      if (cj == 0.0) continue;
      double r_ja[D];
      neighbour_gradient<D>(fluid, s, a, static_cast<std::size_t>(s.via[static_cast<std::size_t>(e)]),
                            r_ja);
      for (int r = 0; r < D; ++r) oa[r] -= cj * r_ja[r];
    }
  }
  // Pair terms: out_a -= K_ab (p_a - p_b), out_b += K_ab (p_a - p_b).
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const auto [a, b] = pairs[k];
    const double* pa = p_of(a);
    const double* pb = p_of(b);
    if (pa == nullptr && pb == nullptr) continue;
    double dp[D], kdp[D];
    for (int r = 0; r < D; ++r) dp[r] = (pa != nullptr ? pa[r] : 0.0) - (pb != nullptr ? pb[r] : 0.0);
    const double* K = &s.pair_k[k * D * D];
    for (int r = 0; r < D; ++r) kdp[r] = dot(K + r * D, dp);
    if (pa != nullptr) {
      double* oa = out + static_cast<std::size_t>(fluid.index(a)) * D;
      for (int r = 0; r < D; ++r) oa[r] -= kdp[r];
    }
    if (pb != nullptr) {
      double* ob = out + static_cast<std::size_t>(fluid.index(b)) * D;
      for (int r = 0; r < D; ++r) ob[r] += kdp[r];
    }
  }
}

template <int D>
void add_pressure_stiffness_reference(const SphParticles& fluid, int free_particles,
                                      const SparseMatrix& pattern, bool definite,
                                      double* values) {
  PressureHessianScratch s;
  prepare<D>(fluid, s);
  const int n = fluid.size();
  const auto& pairs = fluid.pairs();
  auto add = [&](int p, int q, const double (&M)[D][D], double scale) {
    if (p >= free_particles || q >= free_particles) return;
    springlab::add_block<D>(values, find_block_slot(pattern, D, p, q), M, scale);
  };
  // Pair terms: dF_a/dx_a = -K, dF_a/dx_b = +K.
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const auto [p, q] = pairs[k];
    const double coefficient = pair_coefficient<D>(fluid, s, p, q);
    if (coefficient == 0.0) continue;
    double K[D][D];
    pair_block<D>(fluid, k, coefficient, definite, K);
    const int pi = fluid.index(p), qi = fluid.index(q);
    add(pi, pi, K, -1.0);
    add(qi, qi, K, -1.0);
    add(pi, qi, K, 1.0);
    add(qi, pi, K, 1.0);
  }
  // Rank-one terms: block (a, k) -= m_j A'_j R_ja R_jk^T over a, k in {j}
  // and j's neighbours.
  for (int j = 0; j < n; ++j) {
    const std::size_t uj = static_cast<std::size_t>(j);
    const double weight = fluid.mass(j) * s.a_slope[uj];
    if (weight == 0.0) continue;
    std::vector<int> members{j};
    std::vector<double> gradient(s.self.begin() + j * D, s.self.begin() + (j + 1) * D);
    for (int e = s.start[uj]; e < s.start[uj + 1]; ++e) {
      const int other = s.partner[static_cast<std::size_t>(e)];
      double r[D];
      neighbour_gradient<D>(fluid, s, other, static_cast<std::size_t>(s.via[static_cast<std::size_t>(e)]), r);
      members.push_back(other);
      gradient.insert(gradient.end(), r, r + D);
    }
    for (std::size_t t = 0; t < members.size(); ++t) {
      for (std::size_t m = 0; m < members.size(); ++m) {
        double M[D][D];
        for (int r = 0; r < D; ++r) {
          for (int c = 0; c < D; ++c) M[r][c] = gradient[m * D + r] * gradient[t * D + c];
        }
        add(fluid.index(members[m]), fluid.index(members[t]), M, -weight);
      }
    }
  }
}

template void add_pressure_stiffness<2>(const SphParticles&, int, const SparseMatrix&, bool,
                                        double*, PressureHessianScratch&);
template void add_pressure_stiffness<3>(const SphParticles&, int, const SparseMatrix&, bool,
                                        double*, PressureHessianScratch&);
template void add_pressure_stiffness_product<2>(const SphParticles&, int, bool, const double*,
                                                double*, PressureHessianScratch&);
template void add_pressure_stiffness_product<3>(const SphParticles&, int, bool, const double*,
                                                double*, PressureHessianScratch&);
template void add_pressure_stiffness_reference<2>(const SphParticles&, int, const SparseMatrix&,
                                                  bool, double*);
template void add_pressure_stiffness_reference<3>(const SphParticles&, int, const SparseMatrix&,
                                                  bool, double*);

}  // namespace springlab
