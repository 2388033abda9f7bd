"""Cross-validation of the in-house solver against the independent Exudyn models."""
