"""The example mechanism documents of the seed cases (one JSON file each, found by name:
flexmech.load("gripper"), `flexmech solve gripper`, {"example": "gripper"} over HTTP) and the
scripts that run them."""
