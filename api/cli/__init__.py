"""The flexmech command line: solve a mechanism document, sweep a load, list the examples.

    flexmech solve examples/gripper.json --set /loads/actuation/force/1=77 --stiffness
    flexmech solve examples/gripper.json --analysis linearization
    flexmech linearization examples/gripper.json --at undeformed   (a command per analysis)
    flexmech linearize examples/rod_free_vibration.json --at undeformed --state-space rod.mat
    flexmech sweep examples/gripper.json --compare-models --plot sweep.png
    flexmech optimize examples/grasper_shape.json
    flexmech trace examples/snap_through_arch.json --path /loads/P/force/1 --stop -300 --step 20
    flexmech contact examples/gripper_jaw_contact.json --plot force.png --shapes states.png
    flexmech simulate examples/rod_free_vibration.json --until 1 --plot rod.png --animation rod.gif
    flexmech build examples/rod_free_vibration.json   (or --examples: compile the kernels they run on)
    flexmech examples

Exit codes: 0 success; 1 the solver did not converge (status and diagnostics are printed,
and --json/--plot files are still written); 2 a problem with the document or the options,
printed as one line "error: <where>: <problem>" on stderr (a line per field when the document
has several, each with its suggestion: api.cli.problems).

One module per command; importing it registers the command on the shared typer app. The
modules import the physics (NumPy, CasADi, the models) in their commands' bodies, not at their
top, so that --help answers at once (benchmarks/cli_startup.py); the analyses' commands come
from the registry when one runs (api.cli.commands). The `flexmech` script runs main()
(api.cli.leaving): the app, then a quick exit.
"""

from flexmech.api.cli.application import app
from flexmech.api.cli import solve  # noqa: F401 (registers its command)
from flexmech.api.cli import inverse  # noqa: F401
from flexmech.api.cli import optimize  # noqa: F401
from flexmech.api.cli import trace  # noqa: F401
from flexmech.api.cli import sweep  # noqa: F401
from flexmech.api.cli import examples  # noqa: F401
from flexmech.api.cli import batch  # noqa: F401
from flexmech.api.cli import serve  # noqa: F401
from flexmech.api.cli import contact  # noqa: F401
from flexmech.api.cli import simulate  # noqa: F401
from flexmech.api.cli import linearize  # noqa: F401
from flexmech.api.cli import build  # noqa: F401
from flexmech.api.cli import upgrade  # noqa: F401
from flexmech.api.cli import export  # noqa: F401
from flexmech.api.cli import drawing  # noqa: F401
from flexmech.api.cli.leaving import main

__all__ = ["app", "main"]
