"""Load the default robot, map its workspace at a given orientation, and plot it.

    python python/examples/workspace.py [--theta RAD] [--resolution N] [--output workspace.png]
"""
import argparse

import matplotlib

matplotlib.use("Agg")

import pcr  # noqa: E402
import pcr.plot  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", help="pcr-robot JSON (default: the built-in femto-3pf)")
    parser.add_argument("--theta", type=float, default=0.0, help="platform orientation (rad)")
    parser.add_argument("--resolution", type=int, default=41, help="grid points per axis")
    parser.add_argument("--output", default="workspace.png", help="PNG to write")
    args = parser.parse_args()

    robot = pcr.Robot.load(args.robot) if args.robot else pcr.Robot.default()
    ws = pcr.workspace(robot, theta=args.theta, resolution=args.resolution)
    reachable = ws["reachable"]
    cell = (ws["x"][1] - ws["x"][0]) * (ws["y"][1] - ws["y"][0])
    print(f"{robot.name}: {reachable.sum()} of {reachable.size} grid points reachable at "
          f"theta = {args.theta} rad, area ~ {reachable.sum() * cell * 1e6:.1f} mm^2, "
          f"max strain {100 * float(ws['max_strain'][reachable].max()):.3f} %")
    pcr.plot.plot_workspace(robot, result=ws, path=args.output)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
