"""python3 -m gonogo: plots from a gonogo-server, for people who would rather look than read.

    python3 -m gonogo --server @gonogo-endpoint curve --tier bekker --vehicle fed_alpha.json --soil lll_dry_sand --out curve.png
    python3 -m gonogo --server @gonogo-endpoint scalability --tier bekker --vehicle fed_alpha.json --soil lll_dry_sand --out study.png
    python3 -m gonogo --server @gonogo-endpoint quicklook JOB_ID --out map.png

Exit status 0, 2 for a usage error or a local input that cannot be read, 3 when the server refuses.
"""
import argparse
import sys

import matplotlib

matplotlib.use("Agg")

from gonogo import Client, GonogoError, InputError, plots  # noqa: E402


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m gonogo", description=__doc__.split("\n")[0])
    parser.add_argument("--server", help="HOST:PORT or @ENDPOINT_FILE (default: GONOGO_SERVER)")
    parser.add_argument("--token", help="bearer token (default: the endpoint file's, or GONOGO_TOKEN)")
    commands = parser.add_subparsers(dest="command", required=True)

    def wheel_and_soil(p):
        p.add_argument("--tier", required=True)
        p.add_argument("--vehicle", required=True, help="vehicle JSON (clients/vehicles/*.json)")
        p.add_argument("--axle", type=int, default=1, help="axle, 1 = front")
        p.add_argument("--cone-index", type=float, help="cone index, kPa")
        p.add_argument("--soil", help="soil catalogue name")
        p.add_argument("--out", required=True, help="PNG file")

    curve = commands.add_parser("curve", help="a wheel's traction curve: D, T, z and efficiency against slip")
    wheel_and_soil(curve)
    study = commands.add_parser("scalability", help="seed 001's scaled-tyre study")
    wheel_and_soil(study)
    study.add_argument("--scales", default="1,0.5,0.25", help="length ratios, comma-separated, 1 among them")
    look = commands.add_parser("quicklook", help="a finished map job's classes with legend and scale bar")
    look.add_argument("job_id")
    look.add_argument("--out", required=True, help="PNG file")
    args = parser.parse_args(argv)

    try:
        with Client(args.server, token=args.token) as client:
            if args.command == "curve":
                c = client.curve(tier=args.tier, vehicle=args.vehicle, axle=args.axle,
                                 cone_index_kpa=args.cone_index, soil=args.soil, as_dataframe=False)
                fig = plots.plot_curves(c)
            elif args.command == "scalability":
                report = client.scalability(tier=args.tier, vehicle=args.vehicle, axle=args.axle,
                                            cone_index_kpa=args.cone_index, soil=args.soil,
                                            scales=[float(s) for s in args.scales.split(",")])
                fig = plots.plot_scalability(report)
            else:
                job = client.job(args.job_id)
                fig = plots.quicklook(job.rasters()["gonogo"], title=job.message.name)
            fig.savefig(args.out, dpi=120)
            print(args.out)
    except InputError as e:
        print(f"python3 -m gonogo: {e}", file=sys.stderr)
        return 2
    except GonogoError as e:
        print(f"python3 -m gonogo: {e}", file=sys.stderr)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
