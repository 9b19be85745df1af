"""Tuning and diagnosis: system identification, margins, step responses, autotune."""
