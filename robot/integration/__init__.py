"""Time integration: solvers, the event-driven step loop, records."""
