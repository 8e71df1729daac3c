"""The calibration methods, one package each behind one contract (:class:`Method`).

``repeatability`` (report §2.6), ``relative_accuracy`` (§2.8), ``linearity`` (§2.9),
``gauge_check`` (a Type-1 study), ``gauge_linearity`` (AIAG's linearity and bias study),
``gage_rr`` (AIAG's crossed Gage R&R), ``joint_troubleshooting`` (§1.2, §2.8),
``gain_schedule`` (Part IV), ``positioning`` (ISO 230-2, one axis), ``pose_characteristics``
(ISO 9283 §7.2–7.3) and ``stabilisation`` (ISO 9283 §7.4–7.5). The list is
:data:`~station.methods.catalog.BUILT_IN`; a site's own come from its installed packages. A
method package imports the contract and the shared modules beside it, never another method.
"""

from station.methods.catalog import BUILT_IN, method_of, methods, names, session_method
from station.methods.contract import Judgement, Method, MethodInputs, MethodVerdict
from station.methods.report import SessionReport, analyze_session_file, judge, report_session
from station.methods.sessions import SessionSource, load_session_source, session_source

__all__ = [
    "BUILT_IN",
    "Judgement",
    "Method",
    "MethodInputs",
    "MethodVerdict",
    "SessionReport",
    "SessionSource",
    "analyze_session_file",
    "judge",
    "load_session_source",
    "method_of",
    "methods",
    "names",
    "report_session",
    "session_method",
    "session_source",
]
