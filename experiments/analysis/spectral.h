// What one step of a fixed-step method does to the undamped oscillator
// x'' = -w^2 x, read off the method's own steps: the classic measures of
// structural dynamics (Hughes, "The Finite Element Method", 1987, sec. 9.1.2;
// Chung and Hulbert 1993, figs. 1-3).
//
// A fixed-step method on a linear system is a linear recurrence: its state
// after n steps is A^n times the start, A the amplification matrix, of size
// 2 for one-step methods on (x, v), 3 with the Newmark family's kept
// acceleration, 4 for BDF2's previous step. Each scalar component s_n of the
// state then satisfies A's characteristic polynomial,
//   s_{n+d} = c_0 s_n + ... + c_{d-1} s_{n+d-1}   (Cayley-Hamilton),
// so A's eigenvalues are found without opening the method: run it from two
// starts (x = 1, v = 0 and x = 0, v = w) for a few steps, find the degree d
// as the numerical rank of the windows [s_n ... s_{n+4}] (singular values
// above 1e-9 of the largest), fit c by least squares and take the roots.
// The windows start after the first step (BDF2's first step is implicit
// Euler's).
//
// Of the roots lambda: the spectral radius rho = max |lambda|; the principal
// pair is the complex pair of largest modulus, lambda = exp(W h (-xi +- i))
// in Hughes' notation, giving the algorithmic damping ratio
//   xi = -ln |lambda| / arg lambda
// and the relative period error T_h / T - 1 = w h / arg lambda - 1. Where no
// root is complex (the step damps faster than it turns) both are NaN.
#pragma once

#include <string>

#include "integrators/core/integrator.h"

namespace springlab {

struct StepSpectrum {
  double spectral_radius = 0.0;
  double damping_ratio = 0.0;  // NaN without a complex pair
  double period_error = 0.0;   // NaN without a complex pair
  int degree = 0;              // the recurrence's order d (amplification matrix size seen)
};

// Throws std::invalid_argument for an adaptive method (it has no fixed step)
// and std::runtime_error naming the method when a step fails.
StepSpectrum step_spectrum(const std::string& integrator, IntegratorOptions options, double wh);

}  // namespace springlab
