"""Mitsuba rendering."""
