"""The mechanism document: its schema, fields, reading, sections, units of its sections, upgrades."""
