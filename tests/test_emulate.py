"""make emulate: each configuration's environment, and the snapshot it compares against."""

import subprocess

import pytest

from study import emulate


def test_each_configuration_sets_its_switches_and_a_cache_of_its_own():
    caches = set()
    for host, switches in emulate.HOSTS.items():
        env = emulate.environment(host)
        assert {k: env[k] for k in switches} == switches
        assert env["STUDY_CACHE_DIR"].endswith(f"emulate/{host}")
        caches.add(env["STUDY_CACHE_DIR"])
    assert len(caches) == len(emulate.HOSTS)
    with pytest.raises(ValueError, match="unknown configuration 'pentium'"):
        emulate.environment("pentium")


def test_the_snapshot_is_the_committed_one(tmp_path):
    """A reproduce run under emulation rewrites the working tree's tables; verify must compare with HEAD's."""
    tables = emulate.committed_snapshot(tmp_path / "out")
    committed = subprocess.run(["git", "-C", str(emulate.ROOT), "show", "HEAD:reports/tables/errata.csv"],
                               capture_output=True, check=True).stdout
    assert (tables / "errata.csv").read_bytes() == committed
    listed = subprocess.run(["git", "-C", str(emulate.ROOT), "ls-tree", "--name-only", "HEAD", "reports/tables/"],
                            capture_output=True, text=True, check=True).stdout.split()
    assert sorted(p.name for p in tables.iterdir()) == sorted(name.rsplit("/", 1)[1] for name in listed)
