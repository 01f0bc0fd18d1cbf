#pragma once

#include <limits>

// The two constants Newton's loop, its line search, its check of the
// answer and L-BFGS share (one definition, so that "as Newton's" stays
// true).
namespace springlab::newton {

// Sufficient decrease (Armijo): a step of length alpha along d is accepted
// when phi(v + alpha d) <= phi(v) + kArmijo alpha phi'(v) d (Nocedal and
// Wright, Numerical Optimization, eq. 3.4).
inline constexpr double kArmijo = 1e-4;

// Units of round-off: a change below kRoundoff times a quantity's magnitude
// is noise, not progress.
inline constexpr double kRoundoff = 1e3 * std::numeric_limits<double>::epsilon();

}  // namespace springlab::newton
