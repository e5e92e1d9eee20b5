"""Design checks (issue #26): is this design acceptable? Every rule of explorer/checks/registry.py
over the operating range and the tolerances; `check()` returns a CheckReport
(explorer/checks/report.py). The layer sits above studies (it runs the sweep engine) and below cli.
"""

from .report import CheckReport, RuleResult
from .run import check

__all__ = ["CheckReport", "RuleResult", "check"]
