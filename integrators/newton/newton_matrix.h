// The Newton matrix of a velocity-implicit step (velocity_step.h),
//
//   J = M - h w c dF/dv - h^2 w b dF/dx   at a point (t, x, v),
//
// of the exact Jacobians or of their definite parts (each compressed
// spring's negative transverse stiffness dropped: MechanicalSystem::
// definite_jacobians), assembled on the model's pattern value by value.
// The model's calls are counted in the method's statistics.
#pragma once

#include "integrators/core/integrator.h"

namespace springlab {

// The model's calls a solver makes for a method, counted in the method's
// statistics as Integrator::eval_force and eval_jacobians count its own.
class CountedModel {
 public:
  CountedModel() = default;
  CountedModel(const MechanicalSystem& system, IntegratorStats& stats)
      : system_(&system), stats_(&stats) {}
  const MechanicalSystem& system() const { return *system_; }
  IntegratorStats& stats() const { return *stats_; }
  void force(double t, const Vector& x, const Vector& v, Vector& f) const {
    ++stats_->force_evals;
    system_->force(t, x, v, f);
  }
  void jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                 SparseMatrix* dfdv) const {
    ++stats_->jacobian_evals;
    system_->jacobians(t, x, v, dfdx, dfdv);
  }
  void definite_jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                          SparseMatrix* dfdv) const {
    ++stats_->jacobian_evals;
    system_->definite_jacobians(t, x, v, dfdx, dfdv);
  }

 private:
  const MechanicalSystem* system_ = nullptr;
  IntegratorStats* stats_ = nullptr;
};

// Where a linear solver finds the definite matrix of the point its matrix
// was assembled at (the preconditioner is made from it).
class DefiniteMatrixSource {
 public:
  virtual ~DefiniteMatrixSource() = default;
  virtual void assemble_definite(SparseMatrix& out) = 0;
  // The matrix of the point itself (exact, or definite with `definite`),
  // and its product y = J p without it, for a solver handed the point
  // without the matrix (NewtonLinearSolver::defer).
  virtual void assemble_matrix(bool /*definite*/, SparseMatrix& out) { assemble_definite(out); }
  virtual void product(bool /*definite*/, const Vector& /*p*/, Vector& /*y*/) {}
  // The pattern version (MechanicalSystem::pattern_version) of the matrices
  // last assembled: a solver that analysed another pattern starts again.
  virtual long pattern_version() const { return 0; }
};

// A term a method puts in J's dF/dx part in place of some forces' own (the
// discrete gradient's: the derivative of those forces' own discrete
// gradients with respect to the step's end, methods/discrete_gradient_step.h).
class JacobianTerm {
 public:
  virtual ~JacobianTerm() = default;
  // out += cx (the term - those forces' dF/dx) at (t, x), of the exact or
  // the definite matrix.
  virtual void add(double t, const Vector& x, bool definite, double cx,
                   SparseMatrix& out) const = 0;
  // Whether J keeps the symmetry of the model's Jacobians with it.
  virtual bool symmetric(bool definite) const = 0;
};

class NewtonMatrix final : public DefiniteMatrixSource {
 public:
  // The point, the step h and the weighted coefficients b = w b_s and
  // c = w c_s of the scheme (b_s, c_s), so J = M - h c dF/dv - h^2 b dF/dx.
  struct Point {
    double t = 0.0;
    const Vector* x = nullptr;
    const Vector* v = nullptr;
    double h = 0.0, b = 0.0, c = 0.0;
    // A method's own term (nullptr: none); dfdx() keeps dF/dx.
    const JacobianTerm* term = nullptr;
  };
  void set_point(const Point& point) { point_ = point; }
  // out = J at the point, of the exact or the definite Jacobians; dF/dx
  // stays in dfdx().
  void assemble(bool definite, SparseMatrix& out);
  void assemble_definite(SparseMatrix& out) override { assemble(true, out); }
  void assemble_matrix(bool definite, SparseMatrix& out) override { assemble(definite, out); }
  // Whether product() serves at the point: the model gives products of its
  // Jacobians (MechanicalSystem::has_jacobian_products) and the method adds
  // no term of its own.
  bool has_products() const;
  // y = J p at the point, J = M - h c dF/dv - h^2 b dF/dx, by the model's
  // products: J is never assembled.
  void product(bool definite, const Vector& p, Vector& y) override;
  long pattern_version() const override { return model_->system().pattern_version(); }
  // The model of the run (Integrator::initialize).
  void bind(const CountedModel& model) { model_ = &model; }
  const SparseMatrix& dfdx() const { return dfdx_; }
  // A new run: dF/dv may not be needed by the next system.
  void reset() { dfdv_ = SparseMatrix(); }

 private:
  const CountedModel* model_ = nullptr;
  Point point_;
  SparseMatrix dfdx_, dfdv_;
  Vector dfdx_p_, dfdv_p_;  // product()'s
};

}  // namespace springlab
