"""Hostile documents against the C export (issue 47). A document is untrusted input and its
strings reach the export's C sources, header, build files and loader. A corpus of hostile names
(line ends, NUL, comment delimiters, every trigraph, printf conversions, preprocessor lines,
make and shell syntax, rich markup, the templates' own placeholders, non-ASCII, terminal escapes,
the longest name, C keywords, the library's own file names) in one small document whose title
(as long as a name may be: 200 characters, issue 52) carries injections into every file the
export writes: exported over HTTP and by the CLI to the same sources, built
by make with the strict flags and by CMake, its example and checks run, its library loaded
through its loader, every header macro used in a user's translation unit; a canary (code that
would create a file) never fires. The issue's reproductions each have a case of their own (its
title within a name's 200 characters: the issue's own, longer, is refused at the door);
names that cannot become the library's are a 422 naming the field."""

from __future__ import annotations

import io
import json
import re
import subprocess
import sys
import tarfile
from dataclasses import dataclass
from pathlib import Path

import pytest
from c_tools import ensure_c_tools
from conftest import EXAMPLES, sqlite_server
from mechanisms import example_one, sprung_bodies
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.api.client import Client, FlexmechError
from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.service.export.library import export_document
from flexmech.service.export.plan import ExportOptions, _distinct, export_plan

STRICT = "-std=c99 -O2 -Wall -Wextra -Werror"
LIBRARY = "int"  # a C keyword as the library's name: int.c, int_work, INT_OK
CLI_ENV = {"COLUMNS": "200", "NO_COLOR": "1"}
# Each is a load's and an output's name (a name holds no '/', '~' or '.', and at most 64
# characters); the prefix keeps their C names apart.
NAMES = [
    "n01\r#error injected\rint",  # a lone CR: a line end to gcc
    "n02\n#error injected\n int",
    "n03\x00end",
    "n04*",  # its pointer /loads/n04*/force/0 holds "*/"
    "*n05",  # ... and this one "/*"
    "n06??=??(??)??<??>??!??'??-",  # every trigraph but ??/ (a name holds no '/'; the title has it)
    "n07%s%n%x%%",
    "n08 #define X #X",
    "n09\\",
    'n10"',
    "n11$(shell touch canary)",
    "n12`touch canary`",
    "n13 grïpper ☃ \u202e \U0001f600 end",
    "n14\x1b[2J\x1b]0;title\x07",
    "n15\x85\x9b\u2028end",
    "n16" + "L" * 61,  # the longest name
    "n17@TITLE_COMMENT@@SET_PATH@",  # the templates' placeholders
    "n18\"\"\"'''",
    "n19 int main(void) { return 0; }",
    "n20[bold][link=x]",  # rich markup the CLI prints
    "ïï",
    "int",
    "return",
    "while",
    "main",
    "bench",
    "check",
    "example",
    "loader",
    "manifest",
]
BODIES = ['b1\r*??(%n"\\', "*b2`$(x)`ü\x00", "int"]
SWEPT = NAMES[6]  # the example's sweep and the target task: the printf name


# The file a hostile title's command would create, in the folder the build or the run it
# ends up in works in (fired() looks there): a title holds 200 characters, no absolute path.
CANARY = "canary"


def constructor() -> str:
    """C that creates CANARY when a program or library holding it starts (no quote in it: the
    old escaper would have spoiled a string)."""
    command = ",".join(str(byte) for byte in f"touch {CANARY}".encode()) + ",0"
    return (
        "__attribute__((constructor)) static void k(void) {static const char c[]={" + command + "}; if (system(c)) {}}"
    )


def issue_title() -> str:
    """The issue's title, within a name's 200 characters: end the header's first comment, a CR (a
    line end to gcc), declare system() and define a constructor, once per translation unit, and
    open a comment again. (The issue's included <stdlib.h>; a declaration keeps every file of the
    old export building, bench.c's feature macro included, so that the canary is what tells.)"""
    return f"*/\r#ifndef PWN\r#define PWN\rint system(const char*);\r{constructor()}\r#endif\r/*"


def hostile_title() -> str:
    return "".join(
        [
            f'*/\r"""\rimport os; os.system("touch {CANARY}")\r"""\r',  # a comment's end, the loader's docstring
            f"\\\n$(shell touch {CANARY})\r`touch {CANARY}`\rexecute_process(COMMAND touch {CANARY})\r",  # make, CMake
            "@NAME@ @SET_PATH@ @INPUT_LINES@ ??/ /*",  # the templates' placeholders, the trigraph of a backslash
        ]
    )


def hostile_document() -> dict:
    doc = sprung_bodies(BODIES, ground="g??=*")
    doc["name"] = hostile_title()
    for k, name in enumerate(NAMES):
        doc["loads"][name] = {"type": "force", "body": BODIES[k % 3], "force": [0.0, 0.0]}
        doc["outputs"][name] = {"type": "point", "body": BODIES[k % 3]}
    doc["sweep"] = {
        "path": f"/loads/{SWEPT}/force/0",
        "start": 0,
        "until": {"output": f"{SWEPT}.dx", "equals": 0.005},  # 0.5 N on a 100 N/mm spring
    }
    return doc


@dataclass(frozen=True)
class Hostile:
    canary: Path
    http: Path  # the library from POST /v1/exports
    cli: Path  # the library from flexmech export
    manifest: dict


@pytest.fixture(scope="module", autouse=True)
def c_tools():
    ensure_c_tools()


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    server = sqlite_server(tmp_path_factory, "hostile-export", workers=1)
    yield server
    server.stop()


@pytest.fixture(scope="module")
def hostile(server, tmp_path_factory) -> Hostile:
    root = tmp_path_factory.mktemp("hostile")
    canary = root / "canary"
    doc = hostile_document()
    with Client(server.url) as client:
        job = client.export(document=doc, name=LIBRARY)
        data = client.export_archive(job.id, timeout=120)
    with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as tar:
        tar.extractall(root / "http", filter="data")
    (root / "hostile.json").write_text(json.dumps(doc))
    done = CliRunner().invoke(
        app, ["export", str(root / "hostile.json"), "--c", str(root / "cli"), "--name", LIBRARY], env=CLI_ENV
    )
    assert done.exit_code == 0, done.output
    assert "n20[bold][link=x]" in done.output and "\x1b" not in done.output  # text, no markup, no terminal escape
    http = root / "http" / LIBRARY
    return Hostile(canary, http, root / "cli", json.loads((http / "manifest.json").read_text()))


def fired(canary: Path, *folders: Path) -> list[Path]:
    """The canary, and any file the names' and the titles' own commands (touch canary) would have made."""
    return [path for path in (canary, *(folder / "canary" for folder in folders)) if path.exists()]


def run(command: list[str], cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=timeout)
    assert done.returncode == 0, f"{command}: {done.stdout[-3000:]}{done.stderr[-3000:]}"
    return done


def make(folder: Path, *targets: str) -> subprocess.CompletedProcess:
    return run(["make", "-C", str(folder), f"CFLAGS={STRICT}", "CC=gcc", *targets], folder)


def loaded(folder: Path) -> dict:
    """Through the shipped loader.py, in a process of its own: the library's output names and
    the status of one equilibrium call."""
    script = "import json, loader; s = loader.Solver(); status, out, _ = s.equilibrium(); "
    script += "print(json.dumps({'status': status, 'names': list(out)}))"
    return json.loads(run([sys.executable, "-c", script], folder).stdout)


def user_translation_unit(folder: Path, library: str) -> tuple[list[str], subprocess.CompletedProcess]:
    """A user's program that uses every macro of the header, compiled with the strict flags;
    (the macros, its run)."""
    header = (folder / f"{library}.h").read_text()
    guard = f"{library.upper()}_H"
    macros = [m for m in re.findall(r"^#define (\w+)", header, re.MULTILINE) if m != guard]
    used = ",\n".join(f"    (double)({m})" for m in macros)
    source = folder / "user.c"
    source.write_text(
        f'#include <stdio.h>\n#include "{library}.h"\n\nstatic const double used[] = {{\n{used}\n}};\n\n'
        'int main(void) {\n    printf("%d\\n", (int)(sizeof used / sizeof used[0]));\n    return 0;\n}\n'
    )
    run(["gcc", *STRICT.split(), "-pedantic", "user.c", "-o", "user"], folder)
    return macros, run([str(folder / "user")], folder)


def test_over_http_and_by_the_cli_the_hostile_document_gives_the_same_ascii_sources(hostile):
    """Every generated file is ASCII (what is not is escaped or shown as U+XXXX), and the CLI
    writes what the service archives (the manifest but its export time)."""
    http = {p.name: p.read_bytes() for p in hostile.http.iterdir()}
    cli = {p.name: p.read_bytes() for p in hostile.cli.iterdir()}
    assert (
        set(http)
        == set(cli)
        == {
            "int.c",
            "int.h",
            "int_kernels.c",
            "int_kernels.h",
            "main.c",
            "bench.c",
            "check.c",
            "Makefile",
            "CMakeLists.txt",
            "loader.py",
            "manifest.json",
        }
    )
    for name, data in http.items():
        assert data.isascii(), name
        if name != "manifest.json":
            assert data == cli[name], name
    manifests = [json.loads(files["manifest.json"]) for files in (http, cli)]
    for manifest in manifests:
        manifest.pop("export_seconds")
    assert manifests[0] == manifests[1]
    assert manifests[0]["title"] == hostile_title()  # the manifest keeps it whole (JSON)
    assert [o["output"] for o in manifests[0]["outputs"]][:2] == [f"{NAMES[0]}.x", f"{NAMES[0]}.y"]


def test_the_hostile_library_builds_with_strict_flags_and_runs_nothing_of_the_documents(hostile):
    folder = hostile.http
    checked = make(folder, "all", "check")
    assert "check: PASS" in checked.stdout
    example = run([str(folder / "example")], folder).stdout
    header = example.splitlines()[0]
    for label in (f"{SWEPT}.x [mm]", "n06??=??(??)??<??>??!??'??-.dx [mm]", 'n10".y [mm]', "n09\\.x [mm]"):
        assert label in header, label  # data, printed as written
    assert "n01 #error injected int.x [mm]" in header  # a control character printed as a space
    assert f"target: {SWEPT}.dx = 0.005 mm at n07_s_n_x_force_x = 0.50000" in example
    library = loaded(folder)
    assert library["status"] == 0
    assert library["names"] == [o["output"] for o in hostile.manifest["outputs"]]  # the names themselves
    assert f"{NAMES[2]}.x" in library["names"]
    assert fired(hostile.canary, folder) == []


def test_the_hostile_library_builds_and_checks_with_cmake(hostile, tmp_path):
    build = tmp_path / "build"
    run(["cmake", "-S", str(hostile.cli), "-B", str(build)], tmp_path)
    run(["cmake", "--build", str(build), "-j2"], tmp_path)
    tested = run(["ctest", "--output-on-failure"], build)
    assert "100% tests passed" in tested.stdout
    example = run([str(build / "int_example")], build).stdout
    assert f"target: {SWEPT}.dx = 0.005 mm at n07_s_n_x_force_x = 0.50000" in example
    assert fired(hostile.canary, hostile.cli, build) == []


def test_every_macro_of_the_hostile_header_compiles_in_a_users_translation_unit(hostile, tmp_path):
    folder = tmp_path / "user"
    folder.mkdir()
    (folder / "int.h").write_bytes((hostile.http / "int.h").read_bytes())
    macros, program = user_translation_unit(folder, LIBRARY)
    inputs, outputs = len(NAMES) * 2, len(NAMES) * 4  # force x and y; x, y, dx, dy
    assert len([m for m in macros if m.startswith(("INT_IN_", "INT_OUT_"))]) == inputs + outputs + 1  # + OUT_OF_RANGE
    assert {"INT_IN_N04_FORCE_X", "INT_IN_N05_FORCE_Y", "INT_IN_FORCE_X", "INT_OUT_N06_DX", "INT_OUT_DY"} <= set(macros)
    assert program.stdout.strip() == str(len(macros))
    assert fired(hostile.canary, folder) == []


def _exported(tmp_path: Path, doc: dict, name: str) -> Path:
    folder = tmp_path / name
    export_document(load_document(doc), folder, None, ExportOptions(name=name))
    return folder


def _one_body(load: str = "F", output: str = "tip") -> dict:
    doc = sprung_bodies(["b"])
    doc["loads"][load] = {"type": "force", "body": "b", "force": [1.0, 0.0]}
    doc["outputs"][output] = {"type": "point", "body": "b"}
    return doc


def test_the_issues_title_stays_a_comment_and_its_constructor_never_runs(tmp_path):
    canary = tmp_path / "canary"
    doc = _one_body()
    with pytest.raises(MechanismError, match=r"^/name: at most 200 characters \(got 100200\)$"):
        load_document(dict(doc, name=issue_title() + "x" * 100_000))  # a longer title is refused at the door
    doc["name"] = issue_title()
    folder = _exported(tmp_path, doc, "titled")
    make(folder, "all")
    run([str(folder / "example")], folder)
    assert loaded(folder)["status"] == 0
    assert fired(canary, folder) == []
    header = (folder / "titled.h").read_text()
    first = header.splitlines()[0]
    assert first.startswith(
        '/* titled.h: the exported solver of "* / #ifndef PWN #define PWN int system(const char*); '
        "__attribute__((constructor)) static void k(void) {static const char c[]={116,111,117,99,104,"
    )
    assert "\r" not in header and header.index("*/") > header.index("generated, do not edit")


def test_an_output_named_like_a_printf_format_is_printed_as_its_name(tmp_path):
    doc = _one_body(output="e%s%n")
    doc["sweep"] = {"path": "/loads/F/force/0", "start": 0, "until": {"output": "e%s%n.dx", "equals": 0.005}}
    folder = _exported(tmp_path, doc, "printed")
    make(folder, "example")
    example = run([str(folder / "example")], folder).stdout
    assert "e%s%n.x [mm]" in example.splitlines()[0]
    assert "target: e%s%n.dx = 0.005 mm at f_force_x = 0.5" in example
    assert '(%d iterations)\\n", "e%s%n.dx", goal,' in (folder / "main.c").read_text()  # an argument, not a format


def test_a_trigraph_in_an_output_name_builds_under_c99_and_prints_as_written(tmp_path):
    folder = _exported(tmp_path, _one_body(output="e??("), "trigraph")
    make(folder, "all")
    assert "e??(.x [mm]" in run([str(folder / "example")], folder).stdout.splitlines()[0]


def test_a_load_named_act_star_leaves_every_macro_usable(tmp_path):
    folder = _exported(tmp_path, _one_body(load="act*"), "star")
    header = (folder / "star.h").read_text()
    assert "#define STAR_IN_ACT_FORCE_X 0 /* /loads/act* /force/0 [N], range [-inf, inf] */" in header
    macros, program = user_translation_unit(folder, "star")
    assert "STAR_IN_ACT_FORCE_Y" in macros and program.stdout.strip() == str(len(macros))


def test_a_name_truncated_to_40_characters_loses_its_trailing_underscore(tmp_path):
    """CasADi refuses a function name with a double underscore (<name>_kernel_...)."""
    manifest = export_document(load_document(_one_body()), tmp_path / "long", None, ExportOptions(name="a" * 39 + "_b"))
    assert manifest["name"] == "a" * 39


@pytest.mark.parametrize(
    ("title", "name"),
    [("夹持器", "mechanism"), ("Main", "mechanism"), ("Sprung bodies", "sprung_bodies"), ("", "mechanism")],
)
def test_a_library_named_after_the_documents_title_falls_back_to_mechanism(title, name):
    """Without a name the title names the library; one that gives no usable C name (another
    script, a reserved name) gives 'mechanism', as no title does."""
    doc = _one_body()
    doc["name"] = title
    assert export_plan(compile_mechanism(load_document(doc)), "m", ExportOptions()).name == name


REFUSED_NAMES = [
    ("main", "'main' names a file of the export's own (main.c, the example's source): choose another name"),
    ("bench", "'bench' names a file of the export's own (bench.c and the benchmark program bench)"),
    ("check", "'check' names a file of the export's own (check.c and make's target check)"),
    ("Example", "'example' names a file of the export's own (the example program)"),
    ("test", "'test' is a target of make or CMake"),
    ("m", "'m' is a system library the build links (libm)"),
    ("stdio", "stdio.h would stand for the system header <stdio.h> on an include path"),
    ("solve", "'solve' would give functions named as the library's internal ones"),
    ("夹持器", "'夹持器' has no ASCII letter or digit to make the library's C name of"),
]


@pytest.mark.parametrize(("name", "words"), REFUSED_NAMES)
def test_a_name_that_cannot_be_the_librarys_is_422_naming_it(server, name, words):
    with Client(server.url) as client, pytest.raises(FlexmechError) as refused:
        client.export(document=_one_body(), name=name)
    assert refused.value.status == 422 and refused.value.pointer == "/name" and words in refused.value.message


def _force(x: float, y: float) -> dict:
    return {"type": "force", "body": "b", "force": [x, y]}


@pytest.mark.parametrize(
    ("changed", "fields", "pointer", "words"),
    [
        (  # the default inputs: every load
            {"loads": {"F": _force(1, 0), "f": _force(0, 1)}},
            {},
            "/document/loads/f/force/0",
            "'/loads/f/force/0' and '/loads/F/force/0' both become the C name f_force_x: rename one",
        ),
        (
            {"loads": {"F": _force(1, 0), "f": _force(0, 1)}},
            {"inputs": ["/loads/F/force/0", "/loads/f/force/0"]},
            "/inputs/1",
            "'/loads/f/force/0' and '/loads/F/force/0' (/inputs/0) both become the C name f_force_x: rename one",
        ),
        (  # the default outputs: the document's
            {"outputs": {"tip": {"type": "point", "body": "b"}, "Tip": {"type": "point", "body": "b"}}},
            {},
            "/document/outputs/Tip",
            "'Tip.x' and 'tip.x' (/document/outputs/tip) both become the C name tip_x: rename one",
        ),
        (
            {"outputs": {"tip": {"type": "point", "body": "b"}, "Tip": {"type": "point", "body": "b"}}},
            {"outputs": ["tip.y", "tip.x", "Tip.x"]},
            "/outputs/2",
            "'Tip.x' and 'tip.x' (/outputs/1) both become the C name tip_x: rename one",
        ),
        ({"loads": {"n" + "L" * 64: _force(1, 0)}}, {}, "/document/loads/n" + "L" * 64, "at most 64 characters"),
    ],
)
def test_names_that_meet_in_one_c_name_are_422_naming_both(server, changed, fields, pointer, words):
    with Client(server.url) as client, pytest.raises(FlexmechError) as refused:
        client.export(document={**_one_body(), **changed}, name="lib", **fields)
    assert refused.value.status == 422 and refused.value.pointer == pointer and words in refused.value.message


def test_a_non_ascii_library_name_is_exported_mangled_or_refused_naming_it(server, tmp_path):
    """'grïpper' becomes gr_pper (the one mangling); a name without an ASCII letter or digit
    was a CasADi RuntimeError and is a 422 over HTTP and an error naming /name in the CLI."""
    with Client(server.url) as client:
        job = client.export(document=_one_body(), name="grïpper")
        client.wait(job.id, timeout=120)
        assert client.result(job.id).result["manifest"]["name"] == "gr_pper"
    document = tmp_path / "main.json"
    document.write_text(json.dumps(_one_body()))
    for extra, words in (
        (["--name", "夹持器"], "/name: '夹持器' has no ASCII letter or digit"),
        ([], "/name: 'main' names a file of the export's own"),  # the file's name is the default
    ):
        done = CliRunner().invoke(app, ["export", str(document), "--c", str(tmp_path / "c"), *extra], env=CLI_ENV)
        assert done.exit_code == 2 and words in done.output, done.output
    assert not (tmp_path / "c").exists()


def test_contact_outputs_that_meet_in_one_c_name_name_both_fields():
    """The contact task's outputs: a pair named as another but for case (its default outputs),
    and one output given twice."""
    doc = example_one()
    del doc["contacts"]["path"]["outputs"]  # the default: every pair's results
    doc["contacts"]["pairs"]["Insertion"] = dict(doc["contacts"]["pairs"]["insertion"])
    with pytest.raises(MechanismError) as paired:
        export_plan(compile_mechanism(load_document(doc)), "m", ExportOptions())
    assert paired.value.pointer == "/contacts/pairs/Insertion"
    assert paired.value.problem == (
        "'contacts.Insertion.force_x' and 'contacts.insertion.force_x' (/contacts/pairs/insertion) both become "
        "the C name insertion_force_x: rename one"
    )
    assert [p for p, _ in paired.value.problems] == ["/contacts/pairs/Insertion", "/contacts/pairs/insertion"]
    twice = ExportOptions(contact_outputs=("contacts.insertion.gap", "contacts.insertion.gap"))
    with pytest.raises(MechanismError) as repeated:
        export_plan(compile_mechanism(load_document(EXAMPLES / "gripper_jaw_contact.json")), "m", twice)
    assert repeated.value.pointer == "/contact_outputs/1" and "(/contact_outputs/0)" in repeated.value.problem


def test_a_c_name_whose_macro_is_one_of_the_headers_own_is_refused():
    """<NAME>_OUT_OF_RANGE is a status code: an output whose C name is of_range would redefine it."""
    with pytest.raises(MechanismError) as clash:
        _distinct([("/outputs/0", "of.range", "of_range")], "OUT")
    assert clash.value.pointer == "/outputs/0"
    assert clash.value.problem == "'of.range' becomes the macro <NAME>_OUT_OF_RANGE, one of the header's own: rename it"
    _distinct([("/inputs/0", "of.range", "of_range")], "IN")  # <NAME>_IN_OF_RANGE is free
