#include "python_integrator.h"

#include <pybind11/eval.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cctype>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "experiments/kinds/definition_methods.h"
#include "integrators/core/integrator_entry.h"
#include "integrators/registry/registry.h"
#include "models/model/model.h"

namespace py = pybind11;

namespace springlab::python {
namespace {

// The base class, in Python: the attributes `springlab check` and `list`
// read, and the one method to write.
constexpr const char* kIntegratorClass = R"(
class Integrator:
    """A time integrator written in Python (docs/your-own-integrator.md).

    Subclass it and write step(self, model, t, x, v, h) -> (x_new, v_new):
    advance the state from t to t + h. x and v are read-only NumPy views
    of shape (unknowns // d, d); return new arrays. model gives mass(),
    force(t, x, v), stiffness(t, x, v) (dF/dx), damping(t, x, v) (dF/dv),
    jacobians(t, x, v), energies(t, x, v), potential(t, x), ...

    Class attributes (what `springlab.check` tests when given no claim):
      name             registry name (default: the class name in kebab
                       case, MyEuler -> my-euler)
      order            global order of accuracy (default 1)
      implicit         solves a system each step (default False)
      symplectic       (default False)
      stability_limit  largest stable w h on the undamped oscillator
                       (None: not claimed)
      a_stable         stable at every step (default False)
    """
    name = None
    order = 1
    implicit = False
    symplectic = False
    stability_limit = None
    a_stable = False

    def step(self, model, t, x, v, h):
        raise NotImplementedError(type(self).__name__ + ".step(self, model, t, x, v, h) is not written")
)";

py::object& integrator_base() {
  static py::object* base = new py::object();  // leaked: outlives the interpreter's teardown
  return *base;
}

py::object& step_failed() {
  static py::object* type = new py::object();
  return *type;
}

// The exception of a failed step, kept until springlab.run raises it.
std::mutex& error_mutex() {
  static std::mutex m;
  return m;
}
std::optional<py::error_already_set>& step_error() {
  static auto* error = new std::optional<py::error_already_set>();
  return *error;
}

// "MyEuler" -> "my-euler", "RK4Wrong" -> "rk4-wrong".
std::string kebab(const std::string& name) {
  std::string out;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(name[i]);
    if (std::isupper(c) && i > 0 &&
        (std::islower(static_cast<unsigned char>(name[i - 1])) ||
         std::isdigit(static_cast<unsigned char>(name[i - 1])) ||
         (i + 1 < name.size() && std::islower(static_cast<unsigned char>(name[i + 1])) &&
          std::isupper(static_cast<unsigned char>(name[i - 1]))))) {
      out += '-';
    }
    out += c == '_' ? '-' : static_cast<char>(std::tolower(c));
  }
  return out;
}

IntegratorInfo info_of(const py::object& method, const std::string& name) {
  IntegratorInfo info;
  info.name = name;
  const py::object doc = py::type::of(method).attr("__doc__");
  std::string scheme = doc.is_none() ? "" : py::str(doc).cast<std::string>();
  scheme = scheme.substr(0, scheme.find('\n'));
  info.scheme = scheme.empty() ? "a method written in Python" : scheme;
  info.order = method.attr("order").cast<int>();
  info.implicit = method.attr("implicit").cast<bool>();
  // An implicit method reads --newton-tol and --max-newton (model.newton_tol).
  info.iterates_to_tolerance = info.implicit;
  info.symplectic = method.attr("symplectic").cast<bool>();
  if (method.attr("a_stable").cast<bool>()) {
    info.stability = StabilityKind::kA;
    info.stability_limit = kInfinity;
  } else if (!method.attr("stability_limit").is_none()) {
    info.stability = StabilityKind::kConditional;
    info.stability_limit = method.attr("stability_limit").cast<double>();
  }
  return info;
}

// A read-only NumPy view of `data` (owned elsewhere, alive while `owner` is).
py::array view(const double* data, Eigen::Index n, int d, const py::handle& owner) {
  const py::ssize_t rows = d > 0 && n % d == 0 ? n / d : n;
  const py::ssize_t cols = d > 0 && n % d == 0 ? d : 1;
  py::array a;
  if (d > 0 && n % d == 0) {
    a = py::array(py::dtype::of<double>(), {rows, cols},
                  {static_cast<py::ssize_t>(sizeof(double)) * cols, static_cast<py::ssize_t>(sizeof(double))},
                  data, owner);
  } else {
    a = py::array(py::dtype::of<double>(), {static_cast<py::ssize_t>(n)}, {sizeof(double)}, data, owner);
  }
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// A NumPy array that owns the heap Vector `v`.
py::array owning(std::unique_ptr<Vector> v, int d) {
  const double* data = v->data();
  const Eigen::Index n = v->size();
  py::capsule owner(v.release(), [](void* p) { delete static_cast<Vector*>(p); });
  py::array a = view(data, n, d, owner);
  py::detail::array_proxy(a.ptr())->flags |= py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// A SciPy CSC matrix over the arrays of the heap matrix `m` (no copy).
py::object scipy_csc(std::unique_ptr<SparseMatrix> m) {
  static py::object* csc = new py::object(py::module_::import("scipy.sparse").attr("csc_matrix"));
  m->makeCompressed();
  const Eigen::Index n = m->rows(), cols = m->cols(), nnz = m->nonZeros();
  SparseMatrix* raw = m.release();
  py::capsule owner(raw, [](void* p) { delete static_cast<SparseMatrix*>(p); });
  py::array data(py::dtype::of<double>(), {static_cast<py::ssize_t>(nnz)}, {sizeof(double)},
                 raw->valuePtr(), owner);
  py::array indices(py::dtype::of<int>(), {static_cast<py::ssize_t>(nnz)}, {sizeof(int)},
                    raw->innerIndexPtr(), owner);
  py::array indptr(py::dtype::of<int>(), {static_cast<py::ssize_t>(cols + 1)}, {sizeof(int)},
                   raw->outerIndexPtr(), owner);
  return (*csc)(py::make_tuple(data, indices, indptr), py::arg("shape") = py::make_tuple(n, cols),
                py::arg("copy") = false);
}

class PythonMethod;

// What a step is given as `model`.
class ModelView {
 public:
  ModelView(PythonMethod& method, const MechanicalSystem& system, int d)
      : method_(method), system_(system), model_(dynamic_cast<const Model*>(&system)), d_(d) {}

  // One copy per run, read-only: constant through the run.
  py::object mass() {
    if (!mass_) {
      mass_ = owning(std::make_unique<Vector>(system_.mass()), d_);
      py::detail::array_proxy(mass_.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    }
    return mass_;
  }
  py::array force(double t, const py::handle& x, const py::handle& v);
  py::object stiffness(double t, const py::handle& x, const py::handle& v);
  py::object damping(double t, const py::handle& x, const py::handle& v);
  py::tuple jacobians(double t, const py::handle& x, const py::handle& v, bool definite);
  py::dict energies(double t, const py::handle& x, const py::handle& v);
  double potential(double t, const py::handle& x) { return system_.position_potential(t, state(x, xs_)); }
  double dissipation(double t, const py::handle& v) {
    return system_.velocity_potential(t, state(v, vs_));
  }
  bool derives_from_potentials() const { return system_.derives_from_potentials(); }
  Eigen::Index dofs() const { return system_.dofs(); }
  int dimension() const { return d_; }
  py::tuple shape() const {
    return d_ > 0 && system_.dofs() % d_ == 0 ? py::make_tuple(system_.dofs() / d_, d_)
                                              : py::make_tuple(system_.dofs());
  }
  const IntegratorOptions& options() const;
  void count(long newton_iterations, long linear_solves, long factorizations);

  // The state as the system takes it: the method's own vector when `a` is
  // a view of it, otherwise copied into `scratch`.
  const Vector& state(const py::handle& a, Vector& scratch);

 private:
  PythonMethod& method_;
  const MechanicalSystem& system_;
  const Model* model_;
  int d_;
  Vector xs_, vs_;
  py::object mass_;  // null until asked for
};

class PythonMethod final : public Integrator {
 public:
  PythonMethod(IntegratorInfo info, py::object instance)
      : Integrator(std::move(info)), instance_(std::move(instance)) {}
  ~PythonMethod() override {
    py::gil_scoped_acquire gil;
    model_ = py::object();
    step_ = py::object();
    instance_ = py::object();
  }

  // The counted calls, for ModelView.
  void force(double t, const Vector& x, const Vector& v, Vector& f) { eval_force(t, x, v, f); }
  void jacobians(double t, const Vector& x, const Vector& v, SparseMatrix* dfdx,
                 SparseMatrix* dfdv, bool definite) {
    if (definite) {
      eval_definite_jacobians(t, x, v, dfdx, dfdv);
    } else {
      eval_jacobians(t, x, v, dfdx, dfdv);
    }
  }
  // The arrays handed to the step under way (alive while it runs).
  const Vector* step_x() const { return step_x_; }
  const Vector* step_v() const { return step_v_; }
  const IntegratorOptions& run_options() const { return options(); }
  IntegratorStats& run_stats() { return mutable_stats(); }

 protected:
  StepResult do_initialize() override {
    py::gil_scoped_acquire gil;
    const Model* model = dynamic_cast<const Model*>(&system());
    d_ = model != nullptr ? model->dimension() : 0;
    auto view_object = std::make_unique<ModelView>(*this, system(), d_);
    model_ = py::cast(view_object.release(), py::return_value_policy::take_ownership);
    step_ = instance_.attr("step");
    return StepResult::success();
  }

  StepResult do_step(double h) override {
    py::gil_scoped_acquire gil;
    try {
      // Fresh arrays of the state: the method may keep them (x_prev = x)
      // or change them in place; the model takes them back without a copy.
      auto x = std::make_unique<Vector>(x_), v = std::make_unique<Vector>(v_);
      step_x_ = x.get();
      step_v_ = v.get();
      const py::array x_arg = owning(std::move(x), d_), v_arg = owning(std::move(v), d_);
      const py::object result = step_(model_, t_, x_arg, v_arg, h);
      if (!py::isinstance<py::tuple>(result) && !py::isinstance<py::list>(result)) {
        return StepResult::failure(name() + ": step must return (x, v), got " +
                                   py::str(py::type::of(result).attr("__name__")).cast<std::string>());
      }
      const py::sequence pair = result;
      if (pair.size() != 2) {
        return StepResult::failure(name() + ": step must return two arrays (x, v), got " +
                                   std::to_string(pair.size()));
      }
      if (std::string why = take(pair[0], x_, "x"); !why.empty()) return StepResult::failure(why);
      if (std::string why = take(pair[1], v_, "v"); !why.empty()) return StepResult::failure(why);
      return StepResult::success();
    } catch (py::error_already_set& e) {
      std::string what = e.what();
      if (e.matches(step_failed())) {
        // springlab.StepFailed("why"): the run ends as a result, like a
        // built-in's failed Newton solve.
        ++mutable_stats().nonlinear_failures;
        return StepResult::failure(name() + ": " + py::str(e.value()).cast<std::string>());
      }
      {
        std::lock_guard<std::mutex> lock(error_mutex());
        if (!step_error()) step_error() = std::move(e);
      }
      what = what.substr(0, what.find('\n'));
      return StepResult::failure(name() + ": step raised " + what);
    }
  }

 private:
  // Copies a returned array into the state (nothing to copy when it is the
  // state's own view).
  std::string take(const py::handle& returned, Vector& into, const char* what) {
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(returned);
    if (!a) return name() + ": step returned " + what + " that is not an array of numbers";
    if (a.size() != into.size()) {
      return name() + ": step returned " + what + " of " + std::to_string(a.size()) +
             " numbers; the state has " + std::to_string(into.size());
    }
    if (a.data() != into.data()) std::copy(a.data(), a.data() + a.size(), into.data());
    return {};
  }

  py::object instance_, step_, model_;
  int d_ = 0;
  const Vector* step_x_ = nullptr;
  const Vector* step_v_ = nullptr;
};

const IntegratorOptions& ModelView::options() const { return method_.run_options(); }

void ModelView::count(long newton_iterations, long linear_solves, long factorizations) {
  IntegratorStats& s = method_.run_stats();
  s.newton_iterations += newton_iterations;
  s.linear_solves += linear_solves;
  s.factorizations += factorizations;
}

const Vector& ModelView::state(const py::handle& a, Vector& scratch) {
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!array) throw py::type_error("the state must be an array of numbers");
  if (array.size() != system_.dofs()) {
    throw py::value_error("the state must have " + std::to_string(system_.dofs()) +
                          " numbers (shape " + py::str(shape()).cast<std::string>() + "), got " +
                          std::to_string(array.size()));
  }
  for (const Vector* given : {method_.step_x(), method_.step_v()}) {
    if (given != nullptr && array.data() == given->data()) return *given;
  }
  scratch = Eigen::Map<const Vector>(array.data(), array.size());
  return scratch;
}

py::array ModelView::force(double t, const py::handle& x, const py::handle& v) {
  auto f = std::make_unique<Vector>();
  method_.force(t, state(x, xs_), state(v, vs_), *f);
  return owning(std::move(f), d_);
}

py::tuple ModelView::jacobians(double t, const py::handle& x, const py::handle& v, bool definite) {
  auto K = std::make_unique<SparseMatrix>(), D = std::make_unique<SparseMatrix>();
  method_.jacobians(t, state(x, xs_), state(v, vs_), K.get(), D.get(), definite);
  return py::make_tuple(scipy_csc(std::move(K)), scipy_csc(std::move(D)));
}

py::object ModelView::stiffness(double t, const py::handle& x, const py::handle& v) {
  auto K = std::make_unique<SparseMatrix>();
  method_.jacobians(t, state(x, xs_), state(v, vs_), K.get(), nullptr, false);
  return scipy_csc(std::move(K));
}

py::object ModelView::damping(double t, const py::handle& x, const py::handle& v) {
  auto D = std::make_unique<SparseMatrix>();
  method_.jacobians(t, state(x, xs_), state(v, vs_), nullptr, D.get(), false);
  return scipy_csc(std::move(D));
}

py::dict ModelView::energies(double /*t*/, const py::handle& x, const py::handle& v) {
  if (model_ == nullptr) throw py::value_error("this system reports no energy columns");
  const Energies e = model_->energies(state(x, xs_), state(v, vs_));
  py::dict out;
  for (std::size_t c = 0; c < e.columns().size(); ++c) out[py::str(e.columns()[c])] = e.values()[c];
  return out;
}

// One registered Python name: the instance each run copies, and its entry.
struct Slot {
  py::object prototype;
  IntegratorInfo info;
  IntegratorEntry entry;
};
std::map<std::string, Slot*>& slots() {
  static auto* map = new std::map<std::string, Slot*>();  // leaked, like the registry's entries
  return *map;
}

std::unique_ptr<Integrator> make_python_method(Slot* slot) {
  py::gil_scoped_acquire gil;
  py::object copy;
  try {
    copy = py::module_::import("copy").attr("deepcopy")(slot->prototype);
  } catch (py::error_already_set&) {
    copy = slot->prototype;  // not copyable: runs share the instance
  }
  return std::make_unique<PythonMethod>(slot->info, copy);
}

}  // namespace

std::string register_python_method(const py::object& given) {
  py::object method = given;
  if (py::isinstance<py::type>(given)) method = given();
  if (!py::isinstance(method, integrator_base())) {
    // TypeError itself (a C++ exception would become springlab.Error).
    const std::string what = "an integrator is a registered name (str) or an instance of a "
                             "springlab.Integrator subclass, not " +
                             py::str(py::type::of(method).attr("__name__")).cast<std::string>();
    PyErr_SetString(PyExc_TypeError, what.c_str());
    throw py::error_already_set();
  }
  const py::object attribute = method.attr("name");
  const std::string name = attribute.is_none()
                               ? kebab(py::type::of(method).attr("__name__").cast<std::string>())
                               : attribute.cast<std::string>();
  const IntegratorInfo info = info_of(method, name);
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto found = slots().find(name); found != slots().end()) {
    // A class defined again (a notebook cell run twice): the newest counts.
    found->second->prototype = method;
    found->second->info = info;
    return name;
  }
  if (is_integrator(name)) {
    throw std::invalid_argument("'" + name + "' is already the name of a built-in or plug-in "
                                "method: give your class another (name = \"...\")");
  }
  auto* slot = new Slot{method, info, {}};
  slot->entry.name = name;
  slot->entry.make = [slot] { return make_python_method(slot); };
  register_integrator(slot->entry);
  slots()[name] = slot;
  return name;
}

std::string method_name(const py::object& method) {
  if (py::isinstance<py::str>(method)) return method.cast<std::string>();
  return register_python_method(method);
}

bool restore_step_error() {
  std::optional<py::error_already_set> error;
  {
    std::lock_guard<std::mutex> lock(error_mutex());
    error.swap(step_error());
  }
  if (!error) return false;
  error->restore();
  return true;
}

void bind_python_methods(py::module_& m) {
  py::exec(kIntegratorClass, m.attr("__dict__"));
  step_failed() = py::reinterpret_borrow<py::object>(
      py::handle(PyErr_NewExceptionWithDoc("springlab.StepFailed",
                                           "Raised by a step that cannot go on (Newton did not "
                                           "converge): the run ends as a result with this message, "
                                           "as a built-in's failure does.",
                                           PyExc_RuntimeError, nullptr)));
  m.attr("StepFailed") = step_failed();
  integrator_base() = m.attr("Integrator");
  m.attr("Integrator").attr("__module__") = "springlab";

  py::class_<ModelView>(m, "Model",
                        "What a Python method's step(self, model, t, x, v, h) is given: the "
                        "system M x'' = F(t, x, v) over the free unknowns")
      .def("mass", &ModelView::mass, "the lumped mass per unknown, shaped like x (read-only)")
      .def("force", &ModelView::force, py::arg("t"), py::arg("x"), py::arg("v"),
           "F(t, x, v), a new array shaped like x")
      .def("stiffness", &ModelView::stiffness, py::arg("t"), py::arg("x"), py::arg("v"),
           "K = dF/dx, a scipy.sparse.csc_matrix (unknowns x unknowns, x flattened)")
      .def("damping", &ModelView::damping, py::arg("t"), py::arg("x"), py::arg("v"),
           "D = dF/dv, a scipy.sparse.csc_matrix")
      .def("jacobians", &ModelView::jacobians, py::arg("t"), py::arg("x"), py::arg("v"),
           py::arg("definite") = false,
           "(K, D) from one evaluation, on one pattern; definite=True drops each force's "
           "indefinite part (a compressed spring), so M - h D - h^2 K is positive definite")
      .def("energies", &ModelView::energies, py::arg("t"), py::arg("x"), py::arg("v"),
           "the energies by column (kinetic, spring, gravity, ..., total), as --energy writes them")
      .def("potential", &ModelView::potential, py::arg("t"), py::arg("x"),
           "V(t, x): the stored energy of the forces that derive from one (springs, gravity, "
           "elements)")
      .def("dissipation", &ModelView::dissipation, py::arg("t"), py::arg("v"),
           "W(t, v): the dissipation potential of drag and wind (F = -dV/dx - dW/dv)")
      .def_property_readonly("derives_from_potentials", &ModelView::derives_from_potentials,
                             "whether F = -dV/dx - dW/dv (implicit Euler's step then minimises "
                             "|v - v_n|^2_M / 2 + V(x_n + h v) + h W(v))")
      .def_property_readonly("dofs", &ModelView::dofs, "number of unknowns")
      .def_property_readonly("dimension", &ModelView::dimension, "2 or 3")
      .def_property_readonly("shape", &ModelView::shape, "the shape of x and v")
      .def("count", &ModelView::count, py::arg("newton_iterations") = 0, py::arg("linear_solves") = 0,
           py::arg("factorizations") = 0,
           "adds to the run's statistics what the step did beyond the model's calls (which count "
           "themselves: force_evals, jacobian_evals), so run()'s stats report it like a built-in's")
      .def_property_readonly("newton_tol", [](const ModelView& m) { return m.options().newton_tol; },
                             "the run's --newton-tol (m/s)")
      .def_property_readonly("max_newton", [](const ModelView& m) { return m.options().max_newton; },
                             "the run's --max-newton");

  // An experiment definition's "python": [files]: each file's Integrator
  // subclasses are registered (run from Python only).
  set_python_method_loader([](const std::string& path) {
    py::gil_scoped_acquire gil;
    const py::dict names = py::module_::import("runpy").attr("run_path")(path);
    for (const auto& [key, value] : names) {
      if (!py::isinstance<py::type>(value) || value.is(integrator_base())) continue;
      if (PyObject_IsSubclass(value.ptr(), integrator_base().ptr()) == 1) {
        register_python_method(py::reinterpret_borrow<py::object>(value));
      }
    }
  });
}

}  // namespace springlab::python
