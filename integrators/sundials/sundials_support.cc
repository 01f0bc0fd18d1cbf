#include "integrators/sundials/sundials_support.h"

#include <string>

namespace springlab::sundials {

void check(int flag, const char* call, const std::string& detail) {
  if (flag >= 0) return;
  std::string message = std::string(call) + " failed with flag " + std::to_string(flag);
  if (!detail.empty()) message += ": " + detail;
  throw Failure(message);
}

VectorPtr make_vector(Eigen::Index n, SUNContext context) {
  VectorPtr v(check_created(N_VNew_Serial(static_cast<sunindextype>(n), context), "N_VNew_Serial"));
  N_VConst(0.0, v.get());
  return v;
}

void ErrorLog::handler(int error_code, const char* module, const char* function, char* message,
                       void* log) {
  // Warnings (positive codes) are not failures; keep only errors.
  if (error_code >= 0) return;
  static_cast<ErrorLog*>(log)->last =
      std::string(module) + "/" + function + ": " + (message != nullptr ? message : "");
}

}  // namespace springlab::sundials
