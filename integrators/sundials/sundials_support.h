// RAII ownership of SUNDIALS objects and the checks around every call.
// Each object gets a unique_ptr with its destroy function, so an integrator
// that fails half-way through initialization frees everything it created.
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>
#include <sundials/sundials_nonlinearsolver.h>

#include <Eigen/Core>
#include <memory>
#include <string>

namespace springlab::sundials {

struct ContextDeleter {
  void operator()(SUNContext c) const { SUNContext_Free(&c); }
};
struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct MatrixDeleter {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
struct LinearSolverDeleter {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
struct NonlinearSolverDeleter {
  void operator()(SUNNonlinearSolver s) const { SUNNonlinSolFree(s); }
};

using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextDeleter>;
using VectorPtr = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;
using MatrixPtr = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixDeleter>;
using LinearSolverPtr = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinearSolverDeleter>;
using NonlinearSolverPtr =
    std::unique_ptr<std::remove_pointer_t<SUNNonlinearSolver>, NonlinearSolverDeleter>;

// The integrator memory (CVODE, IDA, ARKStep, ERKStep) with its free function.
class SolverMemory {
 public:
  using FreeFn = void (*)(void**);
  SolverMemory() = default;
  SolverMemory(void* memory, FreeFn free_fn) : memory_(memory), free_(free_fn) {}
  SolverMemory(SolverMemory&& other) noexcept { *this = std::move(other); }
  SolverMemory& operator=(SolverMemory&& other) noexcept {
    reset();
    memory_ = other.memory_;
    free_ = other.free_;
    other.memory_ = nullptr;
    return *this;
  }
  SolverMemory(const SolverMemory&) = delete;
  SolverMemory& operator=(const SolverMemory&) = delete;
  ~SolverMemory() { reset(); }
  void reset() {
    if (memory_ != nullptr) free_(&memory_);
    memory_ = nullptr;
  }
  void* get() const { return memory_; }

 private:
  void* memory_ = nullptr;
  FreeFn free_ = nullptr;
};

// Thrown inside initialization and turned into a StepResult by the caller;
// the message names the call that failed.
class Failure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Checks a return code (0 or positive = success) or a created pointer.
void check(int flag, const char* call, const std::string& detail = {});
template <class T>
T* check_created(T* object, const char* call) {
  if (object == nullptr) throw Failure(std::string(call) + " returned NULL");
  return object;
}

// A serial N_Vector of length n (zeroed), and Eigen views of one.
VectorPtr make_vector(Eigen::Index n, SUNContext context);
inline Eigen::Map<Eigen::VectorXd> view(N_Vector v) {
  return {N_VGetArrayPointer(v), static_cast<Eigen::Index>(N_VGetLength(v))};
}

// Collects the last error a solver reports through its error handler, so a
// failure message says what SUNDIALS said instead of printing to stderr.
struct ErrorLog {
  std::string last;
  static void handler(int error_code, const char* module, const char* function, char* message,
                      void* log);
};

}  // namespace springlab::sundials
