"""Built-in defaults used when the user gives no arguments."""
from robodesign.core.paths import DEFAULT_MODULE_SET  # noqa: F401  (re-exported)

# A 6-DoF arm of the built-in set (assets/modules/robodesign_arm/README.md, example A, reach ≈ 0.98 m)
DEFAULT_ORDER = ("1", "21", "22", "4", "22", "3", "23", "24", "23", "12")
