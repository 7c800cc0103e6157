"""backends.versions.installed_version reads only the metadata's header lines: it must give what
importlib.metadata.version gives, for every engine's distribution and for this tool's own."""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

import pytest

from backends.registry import list_backends
from backends.versions import installed_version

DISTRIBUTIONS = sorted({e.distribution for e in list_backends(include_hidden=True)} | {"physics-scenarios"})


@pytest.mark.parametrize("name", DISTRIBUTIONS)
def test_the_version_is_importlib_metadatas(name: str) -> None:
    try:
        expected = version(name)
    except PackageNotFoundError:
        with pytest.raises(PackageNotFoundError):
            installed_version(name)
        return
    assert installed_version(name) == expected


def test_a_missing_distribution_is_package_not_found() -> None:
    with pytest.raises(PackageNotFoundError):
        installed_version("no-such-distribution-physics-scenarios")
