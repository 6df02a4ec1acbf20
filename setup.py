"""The one import package `flexmech`, made of the repository's floors: models/, service/ and api/
install as flexmech.models, flexmech.service and flexmech.api, and examples/ (documents and
scripts, as data) as flexmech.examples, beside flexmech/ itself, the public surface. An editable
install maps the same names onto the same folders. Metadata and dependencies: pyproject.toml."""

from setuptools import find_packages, setup

FLOORS = ("models", "service", "api")


def packages() -> list[str]:
    found = ["flexmech", "flexmech.examples"]
    for floor in FLOORS:
        found += [f"flexmech.{floor}", *(f"flexmech.{floor}.{name}" for name in find_packages(floor))]
    return found


setup(
    packages=packages(),
    package_dir={"flexmech": "flexmech", "flexmech.examples": "examples", **{f"flexmech.{f}": f for f in FLOORS}},
    package_data={
        "flexmech.models": ["*.json"],
        "flexmech.service": ["export/templates/*"],
        "flexmech.api": ["web/*.html", "web/*.js", "web/*.css", "web/*.svg", "web/vendor/*.js", "web/vendor/*.txt"],
        "flexmech.examples": ["*.json", "*.py", "old_documents/*.json"],
    },
)
