"""gonogo's Python client: maps, traction curves and the scalability study from gonogo-server.

    from gonogo import Client
    client = Client("@gonogo-endpoint")          # or "127.0.0.1:50051", or Client() with GONOGO_SERVER
    job = client.submit_map(tier="empirical", vehicle="clients/vehicles/fed_alpha.json",
                            cone_index="ci.tif", elevation="dem.tif")
    job.wait(progress=True)
    files = job.download("out/map")
    curve = client.curve(tier="bekker", vehicle="clients/vehicles/fed_alpha.json", soil="lll_dry_sand")

Every refusal is a GonogoError carrying the gRPC code and the field the server named.
"""
import json
import os
import sys
import tempfile

import grpc
import numpy as np
from google.protobuf import json_format

from gonogo.errors import GonogoError, InputError, JobFailed
from gonogo.v1 import mobility_pb2 as pb
from gonogo.v1 import mobility_pb2_grpc as pb_grpc

GRAVITY_M_S2 = 9.80665
_CHUNK_BYTES = 1 << 20
_ROLES = {
    "cone_index": pb.RASTER_ROLE_CONE_INDEX,
    "slope": pb.RASTER_ROLE_SLOPE,
    "elevation": pb.RASTER_ROLE_ELEVATION,
    "soil_class": pb.RASTER_ROLE_SOIL_CLASS,
}
_ENDED = {pb.JOB_STATE_DONE, pb.JOB_STATE_FAILED, pb.JOB_STATE_CANCELLED}

# The fields of a traction curve's points, in SI units, as a NumPy structured dtype.
CURVE_DTYPE = np.dtype([
    ("slip", "f8"),                 # s = 1 - V / (omega r), -
    ("drawbar_pull_n", "f8"),       # D, N
    ("torque_nm", "f8"),            # T, N m
    ("sinkage_m", "f8"),            # z, m
    ("tractive_efficiency", "f8"),  # eta, -
    ("gross_traction_n", "f8"),     # T / r, N
    ("motion_resistance_n", "f8"),  # N
])


def _call(method, request, **kwargs):
    try:
        return method(request, **kwargs)
    except grpc.RpcError as e:
        raise GonogoError.from_rpc_error(e) from None


def read_endpoint_file(path):
    """(HOST:PORT, token or None) from an endpoint file gonogo-server wrote."""
    try:
        with open(path) as f:
            lines = [line.strip() for line in f.read().splitlines() if line.strip()]
    except OSError as e:
        raise InputError("endpoint_file", f"cannot read {path}: {e.strerror}") from None
    if not lines:
        raise InputError("endpoint_file", f"{path} is empty")
    return lines[0], (lines[1] if len(lines) > 1 else None)


def _message_from(value, message_type, field):
    """A protobuf message from a message, a dict, or the path of a JSON file (the CLI's formats)."""
    if isinstance(value, message_type):
        return value
    if isinstance(value, (str, os.PathLike)):
        try:
            with open(value) as f:
                value = json.load(f)
        except OSError as e:
            raise InputError(field, f"cannot read {value}: {e.strerror}") from None
        except json.JSONDecodeError as e:
            raise InputError(field, f"{value} is not JSON: {e}") from None
    if not isinstance(value, dict):
        raise InputError(field, "give a path to a JSON file, a dict or a message")
    try:
        return json_format.ParseDict(value, message_type())
    except json_format.ParseError as e:
        raise InputError(field, str(e)) from None


def _soil(cone_index_kpa, soil_name, soil_parameters):
    """A pb.SoilState: cone index (kPa, sent in Pa), a catalogue name and/or explicit parameters."""
    state = pb.SoilState()
    if cone_index_kpa is not None:
        state.cone_index_pa = cone_index_kpa * 1000.0
    if soil_name:
        state.soil_name = soil_name
    if soil_parameters:
        state.parameters.CopyFrom(_message_from(dict(soil_parameters), pb.SoilParameterSet, "soil_parameters"))
    return state


def curve_points(points):
    """TractionPoint messages as a NumPy structured array (CURVE_DTYPE)."""
    return np.array([tuple(getattr(p, name) for name in CURVE_DTYPE.names) for p in points],
                    dtype=CURVE_DTYPE)


def _maybe_dataframe(array, as_dataframe):
    if as_dataframe is False:
        return array
    try:
        import pandas
    except ImportError:
        if as_dataframe:
            raise
        return array
    return pandas.DataFrame(array)


class Curve:
    """A traction curve: `points` (NumPy structured array or pandas DataFrame), the wheel and soil
    as computed, and the provenance (tier, cache key, cache hit, who computed it)."""

    def __init__(self, message, as_dataframe=None):
        self.message = message
        self.points = _maybe_dataframe(curve_points(message.points), as_dataframe)
        self.tyre = json_format.MessageToDict(message.tyre, preserving_proto_field_name=True)
        self.wheel_load_n = message.wheel_load_n
        self.soil = json_format.MessageToDict(message.soil, preserving_proto_field_name=True)
        self.provenance = json_format.MessageToDict(message.provenance, preserving_proto_field_name=True)

    def __repr__(self):
        return (f"Curve({self.provenance.get('tier')}, {len(self.message.points)} points, "
                f"load {self.wheel_load_n:.0f} N, key {self.provenance.get('cache_key')})")


class Job:
    """A job on the server: wait for it, download its products, read its rasters."""

    def __init__(self, client, message):
        self._client = client
        self.message = message
        self.id = message.job_id

    def status(self):
        """The job's current pb.JobStatus (state, fraction_done, tasks_done, cache_hits, message)."""
        self.message = _call(self._client._stub.GetJob, pb.GetJobRequest(job_id=self.id),
                             metadata=self._client._metadata)
        return self.message.status

    @property
    def state(self):
        return pb.JobState.Name(self.message.status.state).replace("JOB_STATE_", "")

    def wait(self, progress=False, timeout_s=None):
        """Follows the job until it ends. Returns its last status when DONE; raises JobFailed when it
        FAILED or was cancelled. `progress`: a bar on stderr (True) or a callable given each status."""
        bar = _ProgressBar() if progress and not callable(progress) else None
        show = bar or (progress if callable(progress) else None)
        last = None
        try:
            stream = self._client._stub.WatchJob(pb.WatchJobRequest(job_id=self.id),
                                                 metadata=self._client._metadata, timeout=timeout_s)
            for status in stream:
                last = status
                if show:
                    show(status)
        except grpc.RpcError as e:
            raise GonogoError.from_rpc_error(e) from None
        finally:
            if bar:
                sys.stderr.write("\n")
        if last is None:
            last = self.status()
        self.message.status.CopyFrom(last)
        if last.state != pb.JOB_STATE_DONE:
            raise JobFailed(self.id, self.state, last.message)
        return last

    def download(self, out_dir, product=None):
        """Writes the finished job's products (or one of them) into `out_dir`; returns their paths."""
        os.makedirs(out_dir, exist_ok=True)
        files = {}
        try:
            for chunk in self._client._stub.DownloadResult(
                    pb.DownloadResultRequest(job_id=self.id, product=product or ""),
                    metadata=self._client._metadata):
                name = os.path.basename(chunk.product)
                if name not in files:
                    files[name] = open(os.path.join(out_dir, name), "wb")
                files[name].seek(chunk.offset)
                files[name].write(chunk.data)
        except grpc.RpcError as e:
            raise GonogoError.from_rpc_error(e) from None
        finally:
            for f in files.values():
                f.close()
        return [os.path.join(out_dir, name) for name in files]

    def rasters(self, out_dir=None):
        """The class and speed rasters as arrays with their georeferencing:
        {"gonogo": Raster, "speed": Raster}; downloads them first (into `out_dir`, where the files
        stay, or a temporary directory removed once they are read)."""
        from gonogo.rasters import read_raster
        if out_dir is None:
            with tempfile.TemporaryDirectory(prefix=f"gonogo-{self.id}-") as temporary:
                return self.rasters(temporary)
        self.download(out_dir, "gonogo.tif")
        self.download(out_dir, "speed.tif")
        return {name: read_raster(os.path.join(out_dir, name + ".tif")) for name in ("gonogo", "speed")}

    def cancel(self):
        self.message = _call(self._client._stub.CancelJob, pb.CancelJobRequest(job_id=self.id),
                             metadata=self._client._metadata)
        return self.message

    def _summary(self, message_type):
        """The finished job's summary as a `message_type` (waits for the job first)."""
        self.wait()
        self.message = _call(self._client._stub.GetJob, pb.GetJobRequest(job_id=self.id),
                             metadata=self._client._metadata)
        return json_format.Parse(self.message.summary_json, message_type(), ignore_unknown_fields=True)

    def curve(self, as_dataframe=None):
        """A curve job's Curve (Client.submit_curve), once the job is done."""
        return Curve(self._summary(pb.TractionCurve), as_dataframe)

    def model(self):
        """A training job's registered pb.SurrogateModel (Client.train), once the job is done."""
        return self._summary(pb.SurrogateModel)

    def __repr__(self):
        return f"Job({self.id}, {self.state})"


class _ProgressBar:
    """A progress bar on stderr for one job, redrawn when the percentage or the state changes (not
    on every finished task)."""

    def __init__(self):
        self._shown = None

    def __call__(self, status):
        shown = (int(100 * status.fraction_done), status.state)
        if shown == self._shown:
            return
        self._shown = shown
        width = 30
        done = int(width * status.fraction_done)
        sys.stderr.write("\r[%s%s] %3d%%  tasks %d/%d  cache hits %d  %s" % (
            "#" * done, "-" * (width - done), shown[0], status.tasks_done, status.tasks_total,
            status.cache_hits, pb.JobState.Name(status.state).replace("JOB_STATE_", "")))
        sys.stderr.flush()


class Client:
    """A connection to gonogo-server.

    endpoint:  "HOST:PORT", or "@FILE" for an endpoint file (HOST:PORT, and a token on its second line);
               default: the GONOGO_SERVER environment variable, else 127.0.0.1:50051
    token:     bearer token (default: the endpoint file's, else GONOGO_TOKEN)
    tls_ca:    PEM file of the CA that signed the server's certificate: talk TLS
    """

    def __init__(self, endpoint=None, *, endpoint_file=None, token=None, tls_ca=None):
        endpoint = endpoint or os.environ.get("GONOGO_SERVER") or "127.0.0.1:50051"
        file_token = None
        if endpoint_file or endpoint.startswith("@"):
            endpoint, file_token = read_endpoint_file(endpoint_file or endpoint[1:])
        self.endpoint = endpoint
        token = token or file_token or os.environ.get("GONOGO_TOKEN")
        self._metadata = (("authorization", "Bearer " + token),) if token else ()
        options = [("grpc.max_receive_message_length", 64 << 20)]
        if tls_ca:
            with open(tls_ca, "rb") as f:
                credentials = grpc.ssl_channel_credentials(root_certificates=f.read())
            self._channel = grpc.secure_channel(endpoint, credentials, options=options)
        else:
            self._channel = grpc.insecure_channel(endpoint, options=options)
        self._stub = pb_grpc.MobilityServiceStub(self._channel)

    def close(self):
        self._channel.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # --- maps -------------------------------------------------------------------------------------
    def submit_map(self, *, tier, vehicle, cone_index, slope=None, elevation=None, soil_class=None,
                   soil_table=None, name=None, criteria=None, model=None, guard=None, similarity=True):
        """Submits a map job; returns its Job.

        Rasters (cone_index in kPa, slope in percent or elevation in m, soil_class codes) are GeoTIFF
        paths, or (array, geotransform, crs) tuples written through GDAL (crs: WKT, "EPSG:n" or
        anything GDAL's SetFromUserInput takes). vehicle and soil_table: a JSON file (the CLI's
        formats), a dict or a message. criteria: a dict of pb.Criteria fields (design_slip,
        max_slip, go_margin, passes, slip_step). fe-ann: model (a registered model's id) and guard (a
        dict of pb.SurrogateGuard fields: distance_threshold, spread_threshold, pressure_floor_pa,
        fallback_enabled, return_after_steps; those left out keep the server's)."""
        if (slope is None) == (elevation is None):
            raise InputError("slope", "give exactly one of slope and elevation")
        if (soil_class is None) != (soil_table is None):
            raise InputError("soil_table", "soil_class and soil_table go together")
        request = pb.MapRequest(tier=tier, disable_similarity=not similarity, surrogate_model=model or "")
        if guard:
            request.surrogate_guard.CopyFrom(_message_from(guard, pb.SurrogateGuard, "guard"))
        request.vehicle.CopyFrom(_message_from(vehicle, pb.Vehicle, "vehicle"))
        if soil_table is not None:
            request.soil_table.CopyFrom(_message_from(soil_table, pb.SoilTable, "soil_table"))
        if criteria:
            request.criteria.CopyFrom(_message_from(dict(criteria), pb.Criteria, "criteria"))
        rasters = {"cone_index": cone_index, "slope": slope, "elevation": elevation, "soil_class": soil_class}
        from gonogo.rasters import raster_bytes
        payload = {role: raster_bytes(value, role) for role, value in rasters.items() if value is not None}
        request.name = name or (f"map {os.path.splitext(os.path.basename(cone_index))[0]}"
                                if isinstance(cone_index, (str, os.PathLike)) else "map from arrays")

        def messages():
            yield pb.SubmitMapRequest(request=request)
            for role, data in payload.items():
                for offset in range(0, len(data), _CHUNK_BYTES):
                    yield pb.SubmitMapRequest(chunk=pb.RasterChunk(
                        role=_ROLES[role], data=data[offset:offset + _CHUNK_BYTES]))

        job = _call(self._stub.SubmitMap, messages(), metadata=self._metadata)
        return Job(self, job)

    def job(self, job_id):
        """The job `job_id` (NOT_FOUND when it is not yours or does not exist)."""
        return Job(self, _call(self._stub.GetJob, pb.GetJobRequest(job_id=job_id), metadata=self._metadata))

    def jobs(self, limit=50):
        """Your jobs, newest first."""
        resp = _call(self._stub.ListJobs, pb.ListJobsRequest(limit=limit), metadata=self._metadata)
        return [Job(self, j) for j in resp.jobs]

    # --- traction curves --------------------------------------------------------------------------
    @staticmethod
    def wheel_of(vehicle, axle=1):
        """(tyre message, wheel load N) of a vehicle's axle (1 = front), as `gonogo curve --vehicle`."""
        v = _message_from(vehicle, pb.Vehicle, "vehicle")
        if not 1 <= axle <= len(v.axles):
            raise InputError("axle", f"{axle} is not an axle of {v.name} (1..{len(v.axles)})")
        a = v.axles[axle - 1]
        share = a.load_fraction
        if share == 0 and len(v.axles) == 2 and v.wheelbase_m > 0:
            front = 1 - v.cg_behind_front_axle_m / v.wheelbase_m
            share = front if axle == 1 else 1 - front
        return a.tyre, v.mass_kg * GRAVITY_M_S2 * share / max(a.wheels, 1)

    def _wheel(self, vehicle, axle, tyre, wheel_load_n):
        """(tyre message, wheel load N): a vehicle's axle, or a tyre with its load."""
        if vehicle is not None:
            return self.wheel_of(vehicle, axle)
        if tyre is None or wheel_load_n is None:
            raise InputError("tyre", "give a vehicle, or a tyre with wheel_load_n")
        return _message_from(dict(tyre), pb.Tyre, "tyre"), wheel_load_n

    def curve(self, *, tier, vehicle=None, axle=1, tyre=None, wheel_load_n=None, cone_index_kpa=None,
              soil=None, soil_parameters=None, slip_step=0.0, similarity=True, model=None, guard=None,
              as_dataframe=None):
        """One wheel's traction curve (a Curve; its `points` a NumPy structured array, or a pandas
        DataFrame when pandas is installed, unless as_dataframe=False).

        The wheel: a vehicle's axle (vehicle=..., axle=1 front), or tyre (dict of pb.Tyre fields, m,
        Pa) with wheel_load_n. The soil: cone_index_kpa, a catalogue soil name, and/or
        soil_parameters {"model": ..., "values": {...}} in the units `gonogo soils` lists. fe-ann: model
        and guard as for submit_map."""
        request = self._curve_request(tier, vehicle, axle, tyre, wheel_load_n, cone_index_kpa, soil,
                                      soil_parameters, slip_step, similarity, model, guard)
        return Curve(_call(self._stub.GetTractionCurve, request, metadata=self._metadata), as_dataframe)

    def submit_curve(self, *, tier, vehicle=None, axle=1, tyre=None, wheel_load_n=None, cone_index_kpa=None,
                     soil=None, soil_parameters=None, slip_step=0.0, similarity=True, model=None, guard=None):
        """The same curve as a job (a Job; its curve() once done): how a tier that takes minutes
        (fe-de, fe-ann; `tiers()` says) computes a curve that is not cached yet. Any tier may."""
        request = self._curve_request(tier, vehicle, axle, tyre, wheel_load_n, cone_index_kpa, soil,
                                      soil_parameters, slip_step, similarity, model, guard)
        return Job(self, _call(self._stub.SubmitCurve, request, metadata=self._metadata))

    def _curve_request(self, tier, vehicle, axle, tyre, wheel_load_n, cone_index_kpa, soil, soil_parameters,
                       slip_step, similarity, model, guard):
        tyre_message, load = self._wheel(vehicle, axle, tyre, wheel_load_n)
        request = pb.GetTractionCurveRequest(tier=tier, wheel_load_n=load, slip_step=slip_step,
                                             disable_similarity=not similarity, surrogate_model=model or "")
        if guard:
            request.surrogate_guard.CopyFrom(_message_from(guard, pb.SurrogateGuard, "guard"))
        request.tyre.CopyFrom(tyre_message)
        request.soil.CopyFrom(_soil(cone_index_kpa, soil, soil_parameters))
        return request

    # --- fe-ann surrogate models ------------------------------------------------------------------
    def models(self, soil=""):
        """The registered surrogate models (of `soil`, or all), newest first: pb.SurrogateModel
        messages (soil, architecture, data hash, envelope, held-out errors, code version)."""
        resp = _call(self._stub.ListSurrogateModels, pb.ListSurrogateModelsRequest(soil_name=soil),
                     metadata=self._metadata)
        return list(resp.models)

    def train(self, *, soil, **fields):
        """Trains and registers a surrogate model of `soil`'s RVE as a job on the server's pool (a
        Job; its model() once done). `fields`: the other pb.TrainSurrogateRequest fields
        (hidden_widths, from_model, members, epochs, walks, rig_load_n, carried_variables,
        walk_share, fallback_paths_share, floor_packings, pressure_reference_pa, ...)."""
        request = _message_from(dict(fields, soil_name=soil), pb.TrainSurrogateRequest, "train")
        return Job(self, _call(self._stub.TrainSurrogate, request, metadata=self._metadata))

    def list_curves(self, *, tier="", soil="", min_cone_index_kpa=0.0, max_cone_index_kpa=0.0,
                    as_dataframe=None):
        """Every cached curve matching the filters (all pages), as Curve objects."""
        request = pb.ListTractionCurvesRequest(tier=tier, soil_name=soil,
                                               min_cone_index_pa=min_cone_index_kpa * 1000.0,
                                               max_cone_index_pa=max_cone_index_kpa * 1000.0,
                                               page_size=200)
        curves = []
        while True:
            resp = _call(self._stub.ListTractionCurves, request, metadata=self._metadata)
            curves += [Curve(c, as_dataframe) for c in resp.curves]
            if not resp.next_page_token:
                return curves
            request.page_token = resp.next_page_token

    def scalability(self, *, tier, tyre=None, wheel_load_n=None, vehicle=None, axle=1,
                    cone_index_kpa=None, soil=None, scales=(1.0, 0.5, 0.25), slip_step=0.0):
        """Seed 001's scaled-tyre study: the pb.ScalabilityReport (rows per scale with their points
        and the percent inside the full-scale band; plot_png the server's plot)."""
        tyre_message, load = self._wheel(vehicle, axle, tyre, wheel_load_n)
        request = pb.ScalabilityRequest(tier=tier, wheel_load_n=load, scales=list(scales),
                                        slip_step=slip_step)
        request.tyre.CopyFrom(tyre_message)
        request.soil.CopyFrom(_soil(cone_index_kpa, soil, None))
        return _call(self._stub.RunScalability, request, metadata=self._metadata)

    def tiers(self):
        """The server's tiers: [{name, version, summary, reads, ranks, threads, typical_cost}]."""
        resp = _call(self._stub.ListTiers, pb.ListTiersRequest(), metadata=self._metadata)
        return [json_format.MessageToDict(t, preserving_proto_field_name=True) for t in resp.tiers]
