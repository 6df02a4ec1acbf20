"""The results every contact pair reports, by name: contacts.<pair>.<quantity> (the kind
says its unit)."""

PAIR_OUTPUTS = (
    ("force_x", "force"),
    ("force_y", "force"),
    ("normal_force", "force"),
    ("friction_force", "force"),
    ("point_x", "length"),
    ("point_y", "length"),
    ("site_parameter", "length"),
)
