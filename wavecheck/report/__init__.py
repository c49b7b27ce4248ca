"""The check report: its data model and its renderers (text, JSON)."""

from wavecheck.engine import Report
from wavecheck.report.json import render_json, report_dict
from wavecheck.report.text import render_text
from wavecheck.verdict import overall_verdict

__all__ = ["Report", "overall_verdict", "render_json", "render_text", "report_dict"]
