"""Two integrators written in Python, as docs/your-own-integrator.md builds
them: symplectic Euler, then backward Euler with Newton's method. The
experiment definition experiments/own-methods.json draws them in the
report beside the built-ins ("python": ["../examples/my_methods.py"]).

    import springlab
    from my_methods import MyEuler
    r = springlab.run(springlab.load_scene("cloth", n=8), MyEuler(), dt=0.001, t_end=1)
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

import springlab


class MyEuler(springlab.Integrator):
    """symplectic Euler: v' = v + h M^-1 F(t, x, v), x' = x + h v'"""
    order = 1
    symplectic = True
    stability_limit = 2.0  # w h, on the undamped oscillator

    def step(self, model, t, x, v, h):
        v = v + h * model.force(t, x, v) / model.mass()  # kick with the old force
        return x + h * v, v                                # drift with the new velocity


class MyBackwardEuler(springlab.Integrator):
    """backward Euler: M (v' - v) = h F(t + h, x + h v', v'), Newton on v'"""
    order = 1
    implicit = True
    a_stable = True

    def step(self, model, t, x, v, h):
        m = model.mass().ravel()
        v1 = v.copy()                                       # Newton starts from v_n
        for _ in range(model.max_newton):
            x1 = x + h * v1
            # r(v) = M (v - v_n) - h F(t + h, x_n + h v, v) and its matrix
            # A = M - h D - h^2 K (definite: positive definite, a descent direction)
            r = m * (v1 - v).ravel() - h * model.force(t + h, x1, v1).ravel()
            K, D = model.jacobians(t + h, x1, v1, definite=True)
            A = (sp.diags(m) - h * D - h * h * K).tocsc()
            dv = spla.spsolve(A, -r)
            model.count(newton_iterations=1, linear_solves=1, factorizations=1)
            v1 = v1 + dv.reshape(v.shape)
            if np.abs(dv).max() <= model.newton_tol:        # converged (m/s)
                return x + h * v1, v1
        raise springlab.StepFailed("Newton did not converge in %d iterations: try a smaller dt"
                                   % model.max_newton)
