// `springlab check`: a method run against what it claims
// (docs/your-own-integrator.md "Checking it"). Each claim is measured on a
// scene where the lecture's statement is exact, with short runs:
//
//   --order K        the oscillator (k = m = 1, w = 1, exact solution
//                    x = x0 cos t): the largest error of (x, v) over a run
//                    of t = 2.4 at four steps halving from h0, the observed
//                    order the slope of log error against log h over the
//                    three finest; holds when it is >= K - 0.3
//   --stable-limit L the stability search (stability.h) on the oscillator:
//                    the largest stable w h, within 2 % of L
//   --a-stable       the same search stays stable up to w h = 1e4, and runs
//                    of 50 steps at w h = 1, 10, ..., 1e4 keep E <= 2 E_0
//   --symplectic     1e4 periods at w h = min(0.5, L/4): the energy error
//                    E/E_0 - 1 stays, to the end, inside the band it filled
//                    in the first 10 periods (widened by 5 % of its width
//                    and 1e-9): bounded, without drift
//   --dissipative    200 steps at w h = 0.1, 1, 10, 100: no step raises the
//                    energy (beyond 1e-9 relative)
//   --momentum       a free 3-D chain of springs (no gravity, spinning and
//                    drifting) and a free affine body (tumbling-box): the
//                    largest change of linear and angular momentum over
//                    200 steps at w_max h = 0.3, relative to sum m |v| and
//                    sum m |x| |v|, at most 1e-6
//   --deterministic  two runs of the cloth (n = 6, 20 steps) and of the
//                    oscillator give bit-identical final states
//
// Each result carries its numbers and the command that reproduces it. A
// divergence or a solver failure in a claim's runs is that claim's FAIL,
// with the run's message.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "integrators/core/integrator.h"

namespace springlab {

struct Claims {
  std::optional<int> order;
  std::optional<double> stable_limit;  // w h
  bool a_stable = false;
  bool symplectic = false;
  bool dissipative = false;
  bool momentum = false;
  bool deterministic = false;
  bool any() const {
    return order || stable_limit || a_stable || symplectic || dissipative || momentum ||
           deterministic;
  }
};

// The claims `springlab list` states for a method: its order and stability
// (a finite conditional limit, or A- / L-stable) and symplecticity, for a
// fixed-step method; dissipative for an A- or L-stable one-step scalar map
// (|R(i y)| <= 1: the oscillator's energy never rises); deterministic for
// every method. An adaptive method's error control picks its steps: only
// deterministic.
Claims stated_claims(const IntegratorInfo& info);

struct ClaimResult {
  std::string claim;     // the option as typed: "--order 2", "--symplectic"
  bool passed = false;
  std::string measured;  // one line: what was measured against what
  nlohmann::ordered_json figures = nlohmann::ordered_json::object();  // the numbers
  std::string run;       // an ordinary springlab command showing the same ("" if none)
};

// A built-in that states the same claims, run beside the method: not a
// claim, a sanity line ("same trajectory as symplectic-euler").
struct SanityLine {
  std::string builtin;
  double max_difference = 0.0;  // of (x, v) on the oscillator, every step
  double dt = 0.0;
};

struct CheckReport {
  std::string integrator;
  std::vector<ClaimResult> results;
  std::optional<SanityLine> sanity;
  bool passed() const {
    for (const ClaimResult& r : results) {
      if (!r.passed) return false;
    }
    return true;
  }
};

// How a claim's command names the method: "--integrator my-euler --plugin
// ./libmy.so" (so that the printed commands run as they are).
struct CheckSubject {
  std::string integrator;
  std::string method_arguments;  // "--integrator NAME [--plugin P]"
  std::string check_command;     // "springlab check NAME [--plugin P]"
  // A method written in Python: how to make one ("MyEuler()"); the
  // commands are then springlab.run / springlab.check calls.
  std::string python_call = {};
};

// Measures every claim given (throws std::invalid_argument for an unknown
// method or a claim that cannot apply, e.g. --order on an adaptive method).
CheckReport check_claims(const CheckSubject& subject, const Claims& claims);

nlohmann::ordered_json check_report_json(const CheckReport& report);
// The report as lines: "PASS  --order 2   observed 2.00 ...   (springlab ...)".
std::string check_report_text(const CheckReport& report);

}  // namespace springlab
