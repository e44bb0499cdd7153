"""The Python client against a real gonogo-server on a loopback port (started here, with a token).

Run by ctest as python_client_test; by hand:
    GONOGO_BUILD_DIR=build PYTHONPATH=build/python python3 -m pytest clients/python/tests
"""
import glob
import json
import os
import subprocess
import sys
import tempfile
import time

import grpc
import numpy as np
import pytest

import gonogo

SOURCE_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
BUILD_DIR = os.path.abspath(os.environ.get("GONOGO_BUILD_DIR", os.path.join(SOURCE_DIR, "build")))
VEHICLE = os.path.join(SOURCE_DIR, "clients", "vehicles", "fed_alpha.json")


def _start_server(tmp_path_factory, *extra_args):
    work = tmp_path_factory.mktemp("server")
    endpoint_file = work / "endpoint"
    proc = subprocess.Popen(
        [os.path.join(BUILD_DIR, "server", "gonogo-server"), "--data-dir", str(work / "data"),
         "--listen", "127.0.0.1:0", "--endpoint-file", str(endpoint_file), "--generate-token",
         "--threads", "2", *extra_args],
        stdout=subprocess.DEVNULL, stderr=open(work / "server.log", "w"))
    for _ in range(200):
        if endpoint_file.exists() and endpoint_file.stat().st_size > 0:
            break
        time.sleep(0.05)
    else:
        proc.kill()
        pytest.fail("gonogo-server did not write its endpoint file: " + (work / "server.log").read_text())
    return proc, str(endpoint_file)


@pytest.fixture(scope="session")
def server(tmp_path_factory):
    proc, endpoint_file = _start_server(tmp_path_factory)
    yield endpoint_file
    proc.terminate()
    proc.wait(timeout=30)


@pytest.fixture(scope="session")
def tiny_server(tmp_path_factory):
    """A server whose fe-de and fe-ann tiers run the tiny configuration (seconds a curve)."""
    proc, endpoint_file = _start_server(tmp_path_factory, "--fe-de-preset", "tiny")
    yield endpoint_file
    proc.terminate()
    proc.wait(timeout=30)


@pytest.fixture(scope="session")
def terrain(tmp_path_factory):
    out = tmp_path_factory.mktemp("terrain")
    subprocess.run([sys.executable, os.path.join(SOURCE_DIR, "clients", "sample-data", "make_sample_terrain.py"),
                    "--out", str(out), "--size", "40"], check=True, stdout=subprocess.DEVNULL)
    return out


@pytest.fixture
def client(server):
    with gonogo.Client("@" + server) as c:
        yield c


def test_map_from_paths_waits_downloads_and_returns_georeferenced_arrays(client, terrain, tmp_path):
    job = client.submit_map(tier="empirical", vehicle=VEHICLE, cone_index=str(terrain / "cone_index.tif"),
                            elevation=str(terrain / "elevation.tif"), soil_class=str(terrain / "soil_class.tif"),
                            soil_table=str(terrain / "soil_table.json"), name="python paths")
    seen = []
    status = job.wait(progress=seen.append)
    assert status.state == gonogo.client.pb.JOB_STATE_DONE
    assert seen and seen[-1].tasks_done == seen[-1].tasks_total > 0
    files = job.download(tmp_path / "out")
    names = {os.path.basename(f) for f in files}
    assert {"gonogo.tif", "speed.tif", "summary.json"} <= names
    summary = json.load(open(tmp_path / "out" / "summary.json"))
    rasters = job.rasters(tmp_path / "arrays")
    cone = gonogo.read_raster(terrain / "cone_index.tif")
    classes = rasters["gonogo"]
    assert classes.array.shape == cone.array.shape
    assert classes.geotransform == pytest.approx(cone.geotransform)
    assert "UTM" in classes.crs or "Transverse_Mercator" in classes.crs
    valid = classes.array != 255
    assert int(valid.sum()) == summary["cells"]["valid"]
    assert set(np.unique(classes.array[valid])) <= {0, 1, 2}
    assert rasters["speed"].array.dtype == np.float32


def test_map_from_arrays_matches_the_map_from_files(client, terrain):
    cone = gonogo.read_raster(terrain / "cone_index.tif")
    elevation = gonogo.read_raster(terrain / "elevation.tif")
    from_files = client.submit_map(tier="empirical", vehicle=VEHICLE, cone_index=str(terrain / "cone_index.tif"),
                                   elevation=str(terrain / "elevation.tif"))
    from_arrays = client.submit_map(tier="empirical", vehicle=json.load(open(VEHICLE)),
                                    cone_index=(cone.array, cone.geotransform, cone.crs, cone.nodata),
                                    elevation=elevation)
    from_files.wait()
    from_arrays.wait()
    a, b = from_files.rasters()["gonogo"], from_arrays.rasters()["gonogo"]
    np.testing.assert_array_equal(a.array, b.array)
    assert a.geotransform == pytest.approx(b.geotransform)
    # Read without a folder, the rasters leave no download behind.
    for job in (from_files, from_arrays):
        assert glob.glob(os.path.join(tempfile.gettempdir(), f"gonogo-{job.id}-*")) == []


def test_curve_is_a_structured_array_in_si_units(client, server):
    curve = client.curve(tier="empirical", vehicle=VEHICLE, cone_index_kpa=300, slip_step=0.05,
                         as_dataframe=False)
    points = curve.points
    assert points.dtype == gonogo.CURVE_DTYPE
    assert len(points) == 21
    assert points["slip"][0] == pytest.approx(0.0) and points["slip"][-1] == pytest.approx(1.0)
    # The same points the CLI prints for the same wheel and soil.
    csv = subprocess.run([os.path.join(BUILD_DIR, "clients", "gonogo"), "--server", "@" + server, "curve",
                          "--tier", "empirical", "--vehicle", VEHICLE, "--cone-index", "300", "--csv"],
                         check=True, capture_output=True, text=True).stdout
    rows = [line for line in csv.splitlines() if line and line[0].isdigit()]
    cli = np.array([[float(x) for x in line.split(",")] for line in rows])
    assert cli.shape == (21, 7)
    for i, name in enumerate(gonogo.CURVE_DTYPE.names):
        np.testing.assert_allclose(points[name], cli[:, i], rtol=1e-5, atol=1e-6, err_msg=name)  # the CSV has 6 digits
    assert curve.provenance["tier"] == "empirical"
    # The same query again is a cache hit, listed by list_curves.
    again = client.curve(tier="empirical", vehicle=VEHICLE, cone_index_kpa=300, slip_step=0.05,
                         as_dataframe=False)
    assert again.provenance.get("cache_hit") is True
    keys = [c.provenance["cache_key"] for c in client.list_curves(tier="empirical", as_dataframe=False)]
    assert curve.provenance["cache_key"] in keys


def test_a_curve_as_a_job_is_the_curve_of_the_query(client):
    job = client.submit_curve(tier="bekker", vehicle=VEHICLE, soil="lll_dry_sand", slip_step=0.1)
    curve = job.curve(as_dataframe=False)
    assert job.state == "DONE"
    assert curve.provenance["tier"] == "bekker"
    assert len(curve.points) == 11
    queried = client.curve(tier="bekker", vehicle=VEHICLE, soil="lll_dry_sand", slip_step=0.1,
                           as_dataframe=False)
    assert queried.provenance["cache_key"] == curve.provenance["cache_key"]
    np.testing.assert_array_equal(queried.points["drawbar_pull_n"], curve.points["drawbar_pull_n"])


def test_surrogate_models_and_a_refused_training(client):
    assert client.models(soil="seed000_sand_rve100") == []
    with pytest.raises(gonogo.GonogoError) as unknown:
        client.train(soil="no_such_soil", epochs=5)
    assert unknown.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert unknown.value.field == "soil_name"
    with pytest.raises(gonogo.InputError) as misspelt:
        client.train(soil="seed000_sand_rve100", epoch=5)
    assert misspelt.value.field == "train"
    with pytest.raises(gonogo.GonogoError) as no_model:
        client.submit_curve(tier="fe-ann", tyre={"diameter_m": 0.5, "width_m": 0.2, "section_height_m": 0.1},
                            wheel_load_n=1000, soil="seed000_sand_rve100")
    assert no_model.value.code == grpc.StatusCode.FAILED_PRECONDITION
    assert "gonogo train" in no_model.value.message


def test_a_trained_model_computes_an_fe_ann_curve_and_says_how(tiny_server):
    with gonogo.Client("@" + tiny_server) as client:
        # The service tests' small recipe: 20-step paths, 4 walks, a 16 x 16 network, 60 epochs;
        # each held-out path also on another packing of the RVE (the floor under its error).
        job = client.train(soil="seed000_sand_rve100", steps=20, walks=4, epochs=60,
                           hidden_widths=[16, 16], floor_packings=1)
        assert job.wait().state == gonogo.client.pb.JOB_STATE_DONE
        model = job.model()
        assert model.soil_name == "seed000_sand_rve100"
        assert model.architecture == "mlp-16x16-tanh-anchored"
        assert model.fe_de_preset == "tiny"
        assert model.samples > 0 and len(model.held_out) > 0
        assert model.fallback_paths == 0
        floors = [h.packings for h in model.held_out]
        assert len(floors) == 7 and all(len(f) == 1 for f in floors), model.held_out
        assert all(f[0].packing_seed == 2 and f[0].difference > 0 for f in floors), model.held_out
        assert [m.id for m in client.models(soil="seed000_sand_rve100")] == [model.id]

        tyre = {"diameter_m": 0.5, "width_m": 0.2, "section_height_m": 0.1}
        curve_job = client.submit_curve(tier="fe-ann", tyre=tyre, wheel_load_n=1000,
                                        soil="seed000_sand_rve100", slip_step=0.5)
        seen = []
        assert curve_job.wait(progress=seen.append).state == gonogo.client.pb.JOB_STATE_DONE
        # Its progress says how many of its points have fallen back so far (or none).
        assert any("fallen back" in status.message for status in seen), [s.message for s in seen]
        curve = curve_job.curve(as_dataframe=False)
        assert curve.provenance["surrogate_model"] == model.id  # the soil's best, by default
        assert len(curve.points) == 3
        run = curve.provenance["surrogate_run"]
        assert int(run["fe_steps"]) > 0  # int64 fields are strings in protobuf's JSON form
        fallbacks = run.get("fallbacks", 0)
        assert len(run.get("fallback_point_steps", [])) == fallbacks
        assert run.get("fallback_paths_kept", 0) <= fallbacks
        assert int(run["network_point_updates"]) > 0
        # Without a floor, each fallback was flagged by the envelope's distance or the members'
        # spread (or both): the run counts each test's flags.
        by_distance = run.get("fallbacks_beyond_distance", 0)
        by_spread = run.get("fallbacks_beyond_spread", 0)
        assert max(by_distance, by_spread) <= fallbacks <= by_distance + by_spread, run
        again = client.curve(tier="fe-ann", tyre=tyre, wheel_load_n=1000, soil="seed000_sand_rve100",
                             slip_step=0.5, model=model.id, as_dataframe=False)
        assert again.provenance.get("cache_hit") is True
        assert again.provenance["surrogate_run"] == run
        # A request's pressure floor above every stress of the soil: each point is answered by its
        # RVE from its first increment, and the curve's version names the floor.
        floored = client.curve(tier="fe-ann", tyre=tyre, wheel_load_n=1000, soil="seed000_sand_rve100",
                               slip_step=0.5, model=model.id, guard={"pressure_floor_pa": 1e9},
                               as_dataframe=False)
        assert floored.provenance["tier_version"] == "fe-ann-3-tiny-p1e+09", floored.provenance
        floored_run = floored.provenance["surrogate_run"]
        assert all(int(step) == 0 for step in floored_run["fallback_point_steps"]), floored_run
        assert floored_run["fallbacks"] > fallbacks, (floored_run, run)
        assert floored_run["fallbacks_below_pressure_floor"] == floored_run["fallbacks"], floored_run
        assert "fallbacks_below_pressure_floor" not in run, run  # none without a floor


def test_scalability_rows_per_scale(client):
    report = client.scalability(tier="bekker", vehicle=VEHICLE, soil="lll_dry_sand", scales=(1.0, 0.5))
    assert [r.scale for r in report.rows] == [1.0, 0.5]
    assert len(report.rows[0].points) > 0
    assert report.plot_png[:8] == b"\x89PNG\r\n\x1a\n"


def test_refusals_carry_the_grpc_code_and_the_field(client, terrain, server):
    with pytest.raises(gonogo.GonogoError) as bad_tier:
        client.curve(tier="no-such-tier", vehicle=VEHICLE, cone_index_kpa=300)
    assert bad_tier.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert bad_tier.value.field == "tier"
    with pytest.raises(gonogo.GonogoError) as unguarded:
        client.curve(tier="bekker", vehicle=VEHICLE, soil="lll_dry_sand", guard={"fallback_enabled": False})
    assert unguarded.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert unguarded.value.field == "surrogate_guard"
    heavy = json.load(open(VEHICLE))
    heavy["mass_kg"] = 1e9
    with pytest.raises(gonogo.GonogoError) as implausible:
        client.submit_map(tier="empirical", vehicle=heavy, cone_index=str(terrain / "cone_index.tif"),
                          elevation=str(terrain / "elevation.tif"))
    assert implausible.value.code == grpc.StatusCode.INVALID_ARGUMENT
    assert implausible.value.field == "vehicle.mass_kg"
    with pytest.raises(gonogo.GonogoError) as unknown:
        client.job("job-000000000000")
    assert unknown.value.code == grpc.StatusCode.NOT_FOUND
    with pytest.raises(gonogo.InputError) as missing:
        client.submit_map(tier="empirical", vehicle=VEHICLE, cone_index=str(terrain / "missing.tif"),
                          elevation=str(terrain / "elevation.tif"))
    assert missing.value.field == "cone_index"
    host_port, _ = gonogo.read_endpoint_file(server)
    with gonogo.Client(host_port, token="not-the-token") as stranger, pytest.raises(gonogo.GonogoError) as denied:
        stranger.tiers()
    assert denied.value.code == grpc.StatusCode.UNAUTHENTICATED


def _run_module(server, *args):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-m", "gonogo", "--server", "@" + server, *args],
                          capture_output=True, text=True, env=env)


def _has_colour(png, hex_colour):
    import matplotlib.image
    image = matplotlib.image.imread(png)[:, :, :3]
    rgb = np.array([int(hex_colour[i:i + 2], 16) / 255 for i in (1, 3, 5)])
    return bool(np.any(np.all(np.abs(image - rgb) < 0.02, axis=-1)))


def test_the_plot_command_line(client, terrain, server, tmp_path):
    job = client.submit_map(tier="empirical", vehicle=VEHICLE, cone_index=str(terrain / "cone_index.tif"),
                            elevation=str(terrain / "elevation.tif"), name="quicklook")
    job.wait()
    summary_dir = tmp_path / "products"
    job.download(summary_dir, "summary.json")
    classes = json.load(open(summary_dir / "summary.json"))["classes"]
    done = _run_module(server, "quicklook", job.id, "--out", str(tmp_path / "map.png"))
    assert done.returncode == 0, done.stderr
    # Every class the summary counts is drawn in its legend colour.
    for code, (name, colour) in gonogo.plots.CLASS_COLOURS.items():
        if classes[name]["percent_of_valid"] > 1:
            assert _has_colour(tmp_path / "map.png", colour), name
    for command in (["curve", "--tier", "bekker", "--soil", "lll_dry_sand"],
                    ["scalability", "--tier", "bekker", "--soil", "lll_dry_sand", "--scales", "1,0.5"]):
        out = tmp_path / (command[0] + ".png")
        done = _run_module(server, *command, "--vehicle", VEHICLE, "--out", str(out))
        assert done.returncode == 0, done.stderr
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10000
    refused = _run_module(server, "curve", "--tier", "no-such-tier", "--cone-index", "300", "--vehicle", VEHICLE,
                          "--out", str(tmp_path / "x.png"))
    assert refused.returncode == 3 and "INVALID_ARGUMENT" in refused.stderr


def test_curve_as_a_dataframe_when_pandas_is_installed(client):
    pandas = pytest.importorskip("pandas")
    curve = client.curve(tier="empirical", vehicle=VEHICLE, cone_index_kpa=250)
    assert isinstance(curve.points, pandas.DataFrame)
    assert list(curve.points.columns) == list(gonogo.CURVE_DTYPE.names)
    array = client.curve(tier="empirical", vehicle=VEHICLE, cone_index_kpa=250, as_dataframe=False).points
    np.testing.assert_array_equal(curve.points["drawbar_pull_n"].to_numpy(), array["drawbar_pull_n"])
    figure = gonogo.plots.plot_curves(curve)  # plots take either form
    assert len(figure.axes) == 4
