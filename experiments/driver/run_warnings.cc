#include "experiments/driver/run_warnings.h"

#include <sstream>

namespace springlab {

std::string warning_text(const RunWarning& warning, const std::string& integrator) {
  std::ostringstream text;
  text << integrator << ": ";
  switch (warning.code) {
    case WarningCode::kFallback:
      text << warning.steps << (warning.steps == 1 ? " step" : " steps") << " fell back to ";
      switch (warning.fallback) {
        case Fallback::kGenericDiscreteGradient:
          text << "Gonzalez's generic discrete gradient (Newton failed with the forces' own, "
                  "also in 2, 4 and 8 substeps): energy still exact, but those steps do not "
                  "keep a body's angular momentum; a smaller --dt avoids them";
          break;
        case Fallback::kSubsteps:
          text << "2, 4 or 8 substeps (Newton failed on the whole step); a smaller --dt "
                  "avoids them";
          break;
      }
      break;
    case WarningCode::kOvershoot:
      if (warning.rule == VerdictRule::kBodyEnergy) {
        text << "the energy rose more than E_s above its start for ";
      } else {
        text << "the kinetic + spring energy passed --blowup x E_s for ";
      }
      text << warning.steps << (warning.steps == 1 ? " step" : " steps") << ", up to "
           << warning.ratio << " x that bound at t = " << warning.t
           << ", and then fell back below it: the method's overshoot at large w h (Hilber and "
              "Hughes 1978), not a divergence; a smaller --dt, or implicit-euler or bdf2, does "
              "not overshoot";
      break;
  }
  return text.str();
}

std::vector<std::string> warning_texts(const std::vector<RunWarning>& warnings,
                                       const std::string& integrator) {
  std::vector<std::string> lines;
  for (const RunWarning& w : warnings) lines.push_back(warning_text(w, integrator));
  return lines;
}

}  // namespace springlab
