"""The ``bt-arrange`` command line.

``bt-arrange info`` reports the library versions and checks that a headless work cell starts.
Errors a user can cause end in a one-line message and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import sys
from importlib import metadata

from bt_arrange.errors import BtArrangeError

STACK = ("py-trees", "pybullet", "opencv-python-headless", "placo", "ruckig", "numpy")


def _info(_: argparse.Namespace) -> int:
    print(f"bt-arrange {metadata.version('bt-arrange')}")
    for package in STACK:
        try:
            print(f"  {package} {metadata.version(package)}")
        except metadata.PackageNotFoundError:
            print(f"  {package} missing (pip install -e . installs it)")
    from bt_arrange_sim import WorkCell, robot_urdf_path

    with WorkCell() as cell:
        cell.settle(0.1)
        print(f"  robot description: {robot_urdf_path()}")
        print(f"  headless work cell: ok (TCP at {cell.arm.tcp_pose()})")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser, with one sub-command per job."""
    parser = argparse.ArgumentParser(prog="bt-arrange", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"%(prog)s {metadata.version('bt-arrange')}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    info = commands.add_parser("info", help="library versions, and a check that a headless cell starts")
    info.set_defaults(handler=_info)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``bt-arrange`` console script."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.handler(args))
    except BtArrangeError as error:
        print(f"bt-arrange: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("bt-arrange: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
