"""BLAS thread control: the cap reaches the loaded libraries, bad values are refused."""

import pytest
from threadpoolctl import threadpool_info

from flexval.geometry import load_scene
from flexval.reducedmodels.catalogue import parse_model
from flexval.reducedmodels.core import threads
from flexval.reducedmodels.models import run_reduced
from flexval.validation.cli import main


@pytest.fixture
def restore_pools():
    """Put the pools and the module's state back as they were."""
    before = {i["filepath"]: i["num_threads"] for i in threadpool_info()}
    state = threads._requested, threads._applied
    yield
    from threadpoolctl import ThreadpoolController

    for lib in ThreadpoolController().lib_controllers:
        if lib.filepath in before:
            lib.set_num_threads(before[lib.filepath])
    threads._requested, threads._applied = state


def test_building_a_system_caps_every_blas_pool_at_one(restore_pools, monkeypatch):
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=2)  # as OpenBLAS starts on a 2-core machine
    monkeypatch.delenv(threads.ENV_VARIABLE, raising=False)
    threads.request_threads()
    scene = load_scene("open_chain")
    run_reduced(
        scene.mechanism, parse_model("dcmm:1", "<test>", "--model"), scene.load_case("f+"), 3
    )
    blas = [i for i in threadpool_info() if i["user_api"] == "blas"]
    assert blas, "numpy and scipy load a BLAS: threadpoolctl must see it"
    assert {i["num_threads"] for i in blas} == {threads.DEFAULT_THREADS}


@pytest.mark.parametrize(
    "text, expected",
    [
        ("0", 0),
        ("1", 1),
        (f" {threads.MAX_THREADS} ", threads.MAX_THREADS),
        (threads.MAX_THREADS, threads.MAX_THREADS),
    ],
)
def test_requested_threads_reads_whole_numbers(text, expected):
    assert threads.requested_threads(text) == expected


def test_environment_variable_is_the_default(monkeypatch):
    monkeypatch.setenv(threads.ENV_VARIABLE, str(threads.MAX_THREADS))
    assert threads.requested_threads() == threads.MAX_THREADS
    monkeypatch.delenv(threads.ENV_VARIABLE)
    assert threads.requested_threads() == threads.DEFAULT_THREADS


@pytest.mark.parametrize(
    "text",
    [
        "-1",
        "1.5",
        "two",
        "",
        "\u00b2",
        "\u0663",
        str(threads.MAX_THREADS + 1),
        "100000000",
        str(2**63),
    ],
)
def test_bad_cap_is_refused_naming_source_and_value(text):
    with pytest.raises(ValueError, match="--blas-threads.*got"):
        threads.requested_threads(text)


def test_cli_bad_cap_exits_2_naming_the_field(restore_pools, monkeypatch, capsys):
    assert main(["--blas-threads", "x", "info", "open_chain"]) == 2
    assert "'--blas-threads' = 'x'" in capsys.readouterr().err
    monkeypatch.setenv(threads.ENV_VARIABLE, "-2")
    assert main(["info", "open_chain"]) == 2
    assert "'FLEXVAL_BLAS_THREADS' = '-2'" in capsys.readouterr().err
