// Factors that do not fit in memory (issue 38.1): a scene whose estimated
// factor is over the limit is refused before the run with the estimate and
// the limit; an allocation that fails anyway (CHOLMOD's status, Eigen's
// std::bad_alloc) is a failed factorization with out_of_memory() set, never
// a crash. The command line under `ulimit -v` (RLIMIT_AS, set in the child
// before exec) ends with exit 1 and one "springlab: error:" line, or a run
// failed with "out of memory" in its message: never a signal or a hang.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "integrators/linear/sparse_direct_solver.h"
#include "run_process.h"

namespace springlab::test_memory_limits {
namespace {

using namespace springlab::testing;

// The 7-point Laplacian of a k x k x k grid plus the identity: positive
// definite, and its factor fills like a solid's Newton matrix's.
SparseMatrix grid_laplacian(int k) {
  std::vector<Eigen::Triplet<double>> entries;
  auto index = [k](int i, int j, int l) { return (i * k + j) * k + l; };
  for (int i = 0; i < k; ++i) {
    for (int j = 0; j < k; ++j) {
      for (int l = 0; l < k; ++l) {
        const int p = index(i, j, l);
        entries.emplace_back(p, p, 7.0);
        if (i + 1 < k) entries.emplace_back(p, index(i + 1, j, l), -1.0);
        if (i > 0) entries.emplace_back(p, index(i - 1, j, l), -1.0);
        if (j + 1 < k) entries.emplace_back(p, index(i, j + 1, l), -1.0);
        if (j > 0) entries.emplace_back(p, index(i, j - 1, l), -1.0);
        if (l + 1 < k) entries.emplace_back(p, index(i, j, l + 1), -1.0);
        if (l > 0) entries.emplace_back(p, index(i, j, l - 1), -1.0);
      }
    }
  }
  SparseMatrix a(k * k * k, k * k * k);
  a.setFromTriplets(entries.begin(), entries.end());
  a.makeCompressed();
  return a;
}

TEST(MemoryLimits, EstimateIsTheFactorsNonzeros) {
  const SparseMatrix a = grid_laplacian(12);
  const FactorEstimate estimate = estimate_factor(a);
  SparseDirectSolver solver;
  ASSERT_TRUE(solver.factorize(a, MatrixKind::kPositiveDefinite)) << solver.error();
  // The same ordering (AMD): the estimate is CHOLMOD's own count.
  EXPECT_NEAR(estimate.nonzeros, solver.factor_nonzeros(), 1e-9 * estimate.nonzeros);
  EXPECT_DOUBLE_EQ(estimate.bytes, kFactorBytesPerNonzero * estimate.nonzeros);
}

TEST(MemoryLimits, RefusalQuotesTheEstimateAndTheLimit) {
  const SparseMatrix a = grid_laplacian(12);
  EXPECT_EQ(factor_fit_error(a, 1e12), "");
  const std::string why = factor_fit_error(a, 1e5, 0.0);
  EXPECT_NE(why.find("the factor of the 1728 x 1728 matrix needs about "), std::string::npos)
      << why;
  EXPECT_NE(why.find(format_bytes(estimate_factor(a).bytes)), std::string::npos) << why;
  EXPECT_NE(why.find("over the 100 KB this process may allocate"), std::string::npos) << why;

  SparseDirectSolver solver(FactorUse::kSolvedOften);  // simplicial: no BLAS buffer
  solver.set_memory_limit(1e5);
  EXPECT_FALSE(solver.factorize(a, MatrixKind::kPositiveDefinite));
  EXPECT_TRUE(solver.out_of_memory());
  EXPECT_EQ(solver.error(), "out of memory: " + why);
  EXPECT_FALSE(solver.has_factor());
}

TEST(MemoryLimits, FormatBytes) {
  EXPECT_EQ(format_bytes(512), "512 bytes");
  EXPECT_EQ(format_bytes(273.39e6), "273 MB");
  EXPECT_EQ(format_bytes(1.7136e9), "1.71 GB");
  EXPECT_EQ(format_bytes(999.9e6), "1 GB");
}

TEST(MemoryLimits, RlimitAsLowersTheLimit) {
  // In a child: the limit is RLIMIT_AS less what is mapped, below it.
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    rlimit limit{};
    limit.rlim_cur = limit.rlim_max = 4000000000ul;
    if (setrlimit(RLIMIT_AS, &limit) != 0) _exit(2);
    const double bytes = memory_limit_bytes();
    _exit(bytes > 0.0 && bytes < 4e9 ? 0 : 1);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
}

// The allocations themselves failing, the estimate's check switched off:
// CHOLMOD's OUT_OF_MEMORY, Eigen's std::bad_alloc (LDL^T, LU), each a
// failed factorization saying so. In a child with RLIMIT_AS just above what
// it has mapped (BLAS's buffers made first, by a small factorization).
TEST(MemoryLimits, FailedAllocationsAreFailures) {
  const SparseMatrix small = grid_laplacian(6);
  const SparseMatrix large = grid_laplacian(40);  // nnz(L) ~ 2e7: ~250 MB
  for (MatrixKind kind :
       {MatrixKind::kPositiveDefinite, MatrixKind::kSymmetric, MatrixKind::kGeneral}) {
    const pid_t pid = fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      SparseDirectSolver warm;
      if (!warm.factorize(small, MatrixKind::kPositiveDefinite)) _exit(3);
      SparseDirectSolver solver;
      solver.set_memory_limit(std::numeric_limits<double>::infinity());
      std::ifstream statm("/proc/self/statm");
      double pages = 0.0;
      statm >> pages;
      const double mapped = pages * static_cast<double>(sysconf(_SC_PAGE_SIZE));
      rlimit limit{};
      limit.rlim_cur = limit.rlim_max = static_cast<rlim_t>(mapped + 40e6);
      if (setrlimit(RLIMIT_AS, &limit) != 0) _exit(2);
      const bool ok = solver.factorize(large, kind);
      if (ok) _exit(4);
      if (!solver.out_of_memory()) _exit(5);
      if (solver.error().find("out of memory in ") != 0) _exit(6);
      _exit(0);
    }
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFEXITED(status)) << "kind " << static_cast<int>(kind) << ": signal "
                                   << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    EXPECT_EQ(WEXITSTATUS(status), 0) << "kind " << static_cast<int>(kind);
  }
}

class MemoryLimitsCli : public ::testing::Test {
 protected:
  MemoryLimitsCli() : temp_("memory-limits") {
    fs::create_directories(work());
    fs::create_directories(io());
  }
  fs::path work() const { return temp_.path() / "work"; }
  fs::path io() const { return temp_.path() / "io"; }

  ProcessResult run_limited(const std::vector<std::string>& args, double bytes) {
    return run_springlab(args, work(), io(), 60.0, [bytes] {
      // OpenBLAS starts a worker thread per core when it loads, before
      // springlab can set one BLAS thread, and each allocates its 128 MB
      // buffer at once, retrying forever when it cannot (a hang at exit,
      // joining it): docs/reliability.md. One thread, as the solver uses.
      setenv("OPENBLAS_NUM_THREADS", "1", 1);
      rlimit limit{};
      limit.rlim_cur = limit.rlim_max = static_cast<rlim_t>(bytes);
      setrlimit(RLIMIT_AS, &limit);
    });
  }

  // The refusal of a factor over the limit (below).
  std::string refused_up_front(const std::string& integrator);

  TempDir temp_;
};

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::string line;
  for (char c : text) {
    if (c == '\n') {
      out.push_back(line);
      line.clear();
    } else {
      line += c;
    }
  }
  if (!line.empty()) out.push_back(line);
  return out;
}

// `run block -p n=20 --integrator NAME` at 420 MB (the command, at
// a size that takes a second): refused before the run, one line on stderr,
// nothing on stdout. Returns that line.
std::string MemoryLimitsCli::refused_up_front(const std::string& integrator) {
  const std::vector<std::string> args = {"run", "block", "-p", "n=20", "--integrator",
                                         integrator, "--dt", "1e-3", "--t-end", "1e-3"};
  const ProcessResult r = run_limited(args, 420e6);
  EXPECT_TRUE(r.exited) << describe(args, r);
  EXPECT_EQ(r.status, 1) << describe(args, r);
  EXPECT_EQ(r.out, "");
  const std::vector<std::string> err = lines(r.err);
  EXPECT_EQ(err.size(), 1u) << describe(args, r);
  const std::string line = err.empty() ? std::string() : err[0];
  EXPECT_EQ(line.rfind("springlab: error: --integrator " + integrator +
                           ": the factor of the 27783 x 27783 matrix needs about ",
                       0),
            0u)
      << line;
  return line;
}

TEST_F(MemoryLimitsCli, BlockOverTheLimitIsRefusedUpFront) {
  const std::string line = refused_up_front("implicit-euler");
  EXPECT_NE(line.find("this process may allocate: use a coarser mesh"), std::string::npos) << line;
}

// SUNDIALS' reduced solver factors the same matrix: refused up front too,
// with its own way out (GMRES factors nothing).
TEST_F(MemoryLimitsCli, CvodeBdfOverTheLimitIsRefusedUpFront) {
  const std::string line = refused_up_front("cvode-bdf");
  EXPECT_NE(line.find("use a coarser mesh, --linear-solver gmres (it factors nothing)"),
            std::string::npos)
      << line;
}

// Every limit from too little for the scene to enough: an error line and
// exit 1, or a run that failed saying "out of memory", or a completed run;
// never a signal or a hang.
TEST_F(MemoryLimitsCli, NoLimitCrashes) {
  const std::vector<std::string> args = {"run", "block", "-p", "n=16", "--integrator",
                                         "implicit-euler", "--dt", "1e-3", "--t-end", "1e-3"};
  for (double megabytes = 120; megabytes <= 480; megabytes += 40) {
    const ProcessResult r = run_limited(args, megabytes * 1e6);
    const std::string where = std::to_string(megabytes) + " MB: " + describe(args, r);
    ASSERT_TRUE(r.exited) << where;
    ASSERT_FALSE(r.timed_out) << where;
    if (r.status == 1) {
      const std::vector<std::string> err = lines(r.err);
      ASSERT_EQ(err.size(), 1u) << where;
      EXPECT_EQ(err[0].rfind("springlab: error: ", 0), 0u) << where;
    } else {
      ASSERT_EQ(r.status, 0) << where;
      if (r.out.find("status failed") != std::string::npos) {
        EXPECT_NE(r.out.find("out of memory"), std::string::npos) << where;
      } else {
        EXPECT_NE(r.out.find("steps 1,"), std::string::npos) << where;
      }
    }
  }
}

}  // namespace
}  // namespace springlab::test_memory_limits
