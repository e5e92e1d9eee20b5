"""`python -m explorer.checks`: the rule table as markdown (docs/guide/checks.md)."""

from .registry import rules_markdown

print(rules_markdown(), end="")
