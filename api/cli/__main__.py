"""`python -m flexmech.api.cli`: the flexmech command line."""

from flexmech.api.cli import main

main()
