"""`python -m service.cli`: the flexmech command line."""

from service.cli import main

main()
