"""The mode basis and linear solves (modal.model)."""
import numpy as np



def test_solve_linear_scales_columns():
    from modal.model import solve_linear

    x = np.linspace(1, 2, 50)
    design = np.column_stack([1e-17 / x**2, np.ones_like(x)])
    coef = np.array([3e16, 2.0])
    np.testing.assert_allclose(solve_linear(design, design @ coef), coef, rtol=1e-12)
