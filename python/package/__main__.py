"""``python3 -m quadrix map SCANS.tsv --out DIR [--scheduler ADDRESS] [...]``: quadrix.map from a shell.

What ``quadrix map --scheduler ADDRESS`` runs: the same options as the command line's ``quadrix map``;
with ``--scheduler`` each scan's modelling and each pair's registration are tasks on the Dask cluster
of that scheduler (its workers read the clouds from the list's paths: a filesystem they all share),
and the pose graph is solved here. Exit code 2 on bad input or when Dask is missing.
"""

import argparse
import sys
import time


def _parser():
    parser = argparse.ArgumentParser(prog="python3 -m quadrix", description="Quadrix from the shell (see quadrix --help).")
    commands = parser.add_subparsers(dest="command", required=True)
    command = commands.add_parser("map", help="One map from many scans (quadrix map), optionally on a Dask cluster")
    command.add_argument("scans", help="SCANS.tsv: header, then session<TAB>scan<TAB>odometry (12 numbers or -)")
    command.add_argument("--out", required=True, help="Output folder (replaced only once everything is written)")
    command.add_argument("--gt", help="True poses (poses.tsv format): ATE, RPE, loop-edge precision and recall")
    command.add_argument("--scheduler", help="Dask scheduler address (tcp://host:8786): model and register on its workers")
    command.add_argument("--preset", default="auto", help="Registration preset of every scan (vlp64|vlp16|mid360|avia|monument|auto)")
    command.add_argument("--loop-radius", type=float, help="Radius of the loop search right after a loop, m")
    command.add_argument("--loop-radius-growth", type=float, help="Radius growth per metre travelled since the last loop")
    command.add_argument("--minimum-loop-travel", type=float, help="A loop candidate lies at least this far back along the path, m")
    command.add_argument("--candidates-per-scan", type=int, help="Loop candidates registered per scan within a session")
    command.add_argument("--place-candidates", type=int, help="Candidates per scan across sessions (place descriptor)")
    command.add_argument("--maximum-loop-radius", type=float, help="The loop search radius never exceeds this, m")
    command.add_argument("--candidate-spacing", type=float, help="Loop candidates of one scan lie at least this far apart along the path, m")
    command.add_argument("--registration-information", action="store_true",
                         help="Loop edges carry the registration's information instead of fixed sigmas")
    command.add_argument("--information-scale", type=float, help="Scale of the registration's information per inlier, 1/m^2")
    command.add_argument("--odometry-gate", type=float, help="Loop edges within a session departing from the odometry by more "
                         "than this many drift sigmas stay out of the graph (0: no gate)")
    command.add_argument("--no-ambiguous-edges", action="store_true", help="Leave ambiguous loop edges out of the graph")
    command.add_argument("--ambiguous-edges-across-sessions", action="store_true",
                         help="Let ambiguous loop edges between sessions into the graph too")
    command.add_argument("--joint-rounds", type=int,
                         help="Rounds of loop candidates across sessions by radius search in the joint map frame (0: none)")
    command.add_argument("--joint-radius", type=float, help="Radius of that search around each scan's map position, m")
    command.add_argument("--no-ambiguous-joint-edges", action="store_true",
                         help="Leave ambiguous edges of the joint-frame rounds out of the graph")
    command.add_argument("--ambiguous-gate-translation", type=float, help="An ambiguous loop edge enters the graph only within "
                         "this many metres of the map solved without ambiguous edges")
    command.add_argument("--ambiguous-gate-rotation", type=float, help="and within this many degrees")
    command.add_argument("--information-rounds", type=int, help="At most this many rounds of variance component estimation "
                         "after the last solve: each group of edges is weighted by what its residuals measured (0: the information as given)")
    command.add_argument("--place-vote", type=int, help="Ambiguous place edges between two sessions enter the graph when at "
                         "least this many place edges agree on the sessions' relative pose and twice as many as on any contradicting one (0: never)")
    command.add_argument("--outlier-threshold", type=float, help="After the calibration, loop edges leave the graph one at a "
                         "time while the largest chi-square over redundancy exceeds this (0: no test)")
    command.add_argument("--map-voxel", type=float, help="map.ply keeps one point per cube of this edge, m")
    return parser


def _options(arguments):
    """quadrix.map's keyword options from the parsed arguments (only those given)."""
    names = {"loop_radius": "loop_radius", "loop_radius_growth": "loop_radius_growth",
             "minimum_loop_travel": "minimum_loop_travel", "candidates_per_scan": "candidates_per_scan",
             "place_candidates": "place_candidates_per_scan", "map_voxel": "map_voxel",
             "maximum_loop_radius": "maximum_loop_radius", "candidate_spacing": "minimum_candidate_spacing",
             "information_scale": "loop_information_scale", "odometry_gate": "odometry_gate_sigmas",
             "joint_rounds": "joint_rounds", "joint_radius": "joint_radius",
             "ambiguous_gate_translation": "ambiguous_gate_translation",
             "ambiguous_gate_rotation": "ambiguous_gate_rotation_degrees",
             "information_rounds": "information_rounds", "outlier_threshold": "outlier_threshold",
             "place_vote": "place_vote_minimum"}
    options = {"preset": arguments.preset}
    for argument, option in names.items():
        value = getattr(arguments, argument)
        if value is not None:
            options[option] = value
    if arguments.no_ambiguous_edges:
        options["use_ambiguous_edges"] = False
    if arguments.ambiguous_edges_across_sessions:
        options["use_ambiguous_edges_across_sessions"] = True
    if arguments.no_ambiguous_joint_edges:
        options["use_ambiguous_joint_edges"] = False
    if arguments.registration_information:
        options["loop_information_from_registration"] = True
    return options


def main(argv=None):
    arguments = _parser().parse_args(argv)
    import quadrix

    client = None
    if arguments.scheduler:
        try:
            from distributed import Client
        except ImportError as error:
            print("error: --scheduler needs Dask distributed in %s (Debian: apt install python3-distributed): %s"
                  % (sys.executable, error), file=sys.stderr)
            return 2
        try:
            client = Client(arguments.scheduler, timeout="30s")
        except (OSError, TimeoutError) as error:
            print("error: --scheduler: cannot reach the Dask scheduler at %s: %s" % (arguments.scheduler, error), file=sys.stderr)
            return 2
    started = time.monotonic()

    def progress(stage, done, total):
        """The command line's progress line (on a terminal only)."""
        seconds = time.monotonic() - started
        if total > 0 and done > 0:
            line = "%s: %d / %d (%.0f s, about %.0f s left in this stage)" % (stage, done, total, seconds, seconds * (total / done - 1.0))
        else:
            line = "%s: %d (%.0f s)" % (stage, done, seconds)
        sys.stderr.write("\r" + line + "   ")
        sys.stderr.flush()

    try:
        result = quadrix.map(arguments.scans, arguments.out, client=client, gt=arguments.gt,
                             progress=progress if sys.stderr.isatty() else None, **_options(arguments))
    except (ValueError, FileNotFoundError, KeyError, TypeError) as error:
        print("error: %s" % error, file=sys.stderr)
        return 2
    finally:
        if client is not None:
            client.close()
        if sys.stderr.isatty():
            sys.stderr.write("\n")

    edges = result.edges
    loops = [edge for edge in edges if edge["kind"] == "loop"]
    print("map: %d scans in %d sessions, %d loop candidates registered (%d within sessions), %d ok, %d in the graph%s"
          % (len(result.scans), len(set(result.sessions)), len(loops), sum(not e["across_sessions"] for e in loops),
             sum(e["status"] == "ok" for e in loops), sum(e["used"] for e in loops),
             " on %s" % arguments.scheduler if arguments.scheduler else ""))
    graph = result.graph
    print("graph: cost %.4g -> %.4g in %d iterations (%s)"
          % (graph["initial_cost"], graph["final_cost"], graph["iterations"], "converged" if graph["converged"] else "not converged"))
    alone = sum(not joined for joined in result.in_map_frame)
    if alone:
        print("warning: %d scans belong to sessions joined to no other: left in their own frames (frame = own)" % alone)
    timings = result.timings_ms
    print("time: %.1f s, %.0f ms a scan (modelling %.0f ms, registration %.0f ms, graph %.0f ms in all)"
          % (timings["total"] / 1000.0, timings["total"] / len(result.scans), timings["modelling"], timings["registration"],
             timings["graph"]))
    if result.evaluation is not None:
        evaluation = result.evaluation
        print("evaluation: %s" % ", ".join("%s %s" % (key, value) for key, value in evaluation.items()
                                            if isinstance(value, (int, float)) and not isinstance(value, bool)))
    print("wrote %s (poses.tsv, edges.csv, report.json, map.ply, map_model.qsm, map.html)" % arguments.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
