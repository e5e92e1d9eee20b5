"""The design rules, one module each (their table: explorer/checks/registry.py; the contract:
explorer/checks/rule.py)."""
