"""The results tables' schema (placeholder until the documentation lands)."""

SCHEMA_VERSION = 1
