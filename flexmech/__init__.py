"""flexmech: planar compliant mechanisms."""
