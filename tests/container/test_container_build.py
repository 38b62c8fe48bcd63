# SPDX-License-Identifier: MIT
"""Module builds inside the project's container image (docker SDK)."""

import shutil
from pathlib import Path

import pytest

from iec2kmod import container, kbuild

HELLO_SRC = Path(__file__).parent.parent / "qemu" / "hello_module"

pytestmark = pytest.mark.container


def test_hello_module_builds_in_container_with_rt_vermagic(build_image, tmp_path):
    for f in HELLO_SRC.iterdir():
        shutil.copy(f, tmp_path / f.name)
    res = container.build_modules(str(tmp_path), image=build_image)
    assert res.ok, res.output
    assert res.image == build_image
    warnings = [l for l in res.output.splitlines() if "warning:" in l.lower()]
    assert warnings == [], res.output
    ko = tmp_path / "iec2kmod_hello.ko"
    assert ko.is_file()
    # modinfo of the container's own kmod ...
    r = container.run_in_container(str(tmp_path), "modinfo -F vermagic iec2kmod_hello.ko",
                                   image=build_image)
    assert r.ok, r.output
    vermagic = r.output.strip()
    assert "preempt_rt" in vermagic.lower()
    assert vermagic.split()[0] == kbuild.kernel_release()
    # ... agrees with the host's reading of the .modinfo section
    assert kbuild.modinfo(str(ko))["vermagic"][0].strip() == vermagic


def test_container_reports_failures_and_has_no_network(build_image, tmp_path):
    (tmp_path / "Kbuild").write_text("obj-m := broken.o\n")
    (tmp_path / "broken.c").write_text("this is not C;\n")
    res = container.build_modules(str(tmp_path), image=build_image)
    assert not res.ok
    assert "broken.c" in res.output and "error" in res.output
    r = container.run_in_container(str(tmp_path), "cat /sys/class/net/*/address | wc -l; "
                                   "ls /sys/class/net", image=build_image)
    assert r.ok and r.output.split()[1:] == ["lo"]


def test_image_tag_follows_the_recipe(tmp_path, monkeypatch):
    recipe = tmp_path / "containers"
    shutil.copytree(container.recipe_dir(), recipe)
    monkeypatch.setenv("IEC2KMOD_CONTAINER_RECIPE", str(recipe))
    t1 = container.recipe_hash("6.1.0-56-rt-amd64", "6.1.192-2")
    assert t1 == container.recipe_hash("6.1.0-56-rt-amd64", "6.1.192-2")
    assert t1 != container.recipe_hash("6.1.0-57-rt-amd64", "6.1.193-1")
    # what does not make the image does not change its tag (a rebuild is minutes):
    # the package marker that installs the recipe and its documentation
    (recipe / "__init__.py").write_text((recipe / "__init__.py").read_text() + "\nX = 1\n")
    (recipe / "README.md").write_text("changed\n")
    assert t1 == container.recipe_hash("6.1.0-56-rt-amd64", "6.1.192-2")
    # the recipe does
    (recipe / "build-rootfs.sh").write_text((recipe / "build-rootfs.sh").read_text() + "\n#\n")
    t2 = container.recipe_hash("6.1.0-56-rt-amd64", "6.1.192-2")
    assert t1 != t2
    # and so does the configuration given at import
    monkeypatch.setattr(container, "_image_config", lambda rel: ["ENV LANG=C"])
    assert t2 != container.recipe_hash("6.1.0-56-rt-amd64", "6.1.192-2")


def test_debian_mirrors_from_apt_sources(tmp_path):
    one = tmp_path / "sources.list"
    one.write_text("# comment\ndeb [arch=amd64] http://mirror.example/debian bookworm main\n"
                   "deb http://sec.example/debian-security bookworm-security main\n")
    assert container.debian_mirrors([str(one)]) == (
        "http://mirror.example/debian", "http://sec.example/debian-security")
    deb822 = tmp_path / "debian.sources"
    deb822.write_text("Types: deb\nURIs: http://m2.example/debian/\n"
                      "Suites: bookworm bookworm-updates\nComponents: main\n\n"
                      "Types: deb\nURIs: http://s2.example/debian-security\n"
                      "Suites: bookworm-security\nComponents: main\n")
    assert container.debian_mirrors([str(deb822)]) == (
        "http://m2.example/debian", "http://s2.example/debian-security")
    other = tmp_path / "other.list"
    other.write_text("deb https://packages.example/apt cloud-sdk-bookworm main\n")
    with pytest.raises(container.ContainerError):
        container.debian_mirrors([str(other)])
