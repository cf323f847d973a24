#!/usr/bin/env python3
"""Distort (or undistort) a folder of frames on every GPU or core of a Ray cluster.

One Ray actor per GPU (or per core when there is none) holds its own vklens.Warper: the
device, the pipelines and the coordinate maps are built once per actor, then every frame is
a numpy array in, a numpy array out. Outputs are written atomically (a temporary file in the
output folder, then a rename), so an interrupted run leaves only whole frames behind and can
be started again: frames whose output exists are skipped unless --overwrite is given.

  python3 examples/python/batch_ray.py --camera cam.yml --input frames/ --output lens/
  python3 examples/python/batch_ray.py --camera cam.yml --input frames/ --output lens/ \\
      --address auto            # join a running cluster instead of starting a local one

The input frames are pinhole images of --source-camera's size (distort; default: the
camera's own size and intrinsics) or lens images of the camera's size (undistort).
"""

import argparse
import os
import pathlib
import sys
import tempfile
import time

import cv2
import numpy as np
import ray

import vklens

EXTENSIONS = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr"}


def write_atomically(path, image):
    """cv2.imwrite's bytes into a temporary file beside `path`, flushed, then renamed."""
    ok, data = cv2.imencode(path.suffix, image)
    if not ok:
        raise vklens.IoError(f"{path}: OpenCV cannot encode {path.suffix}")
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data.tobytes())
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


@ray.remote
class WarpActor:
    """One device, one Warper, many frames."""

    def __init__(self, camera, options):
        source = options.pop("source_camera")
        self.warper = vklens.Warper(camera, source_camera=source, **options)

    def warp(self, src, dst):
        image = cv2.imread(str(src), cv2.IMREAD_UNCHANGED)
        if image is None:
            raise vklens.IoError(f"{src}: not an image OpenCV can read")
        write_atomically(pathlib.Path(dst), self.warper(image))
        return dst

    def finish(self):
        """Raises if the validation layer (when on) spoke during this actor's work."""
        self.warper.device.check_validation()
        return self.warper.device.name


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--camera", required=True, help="the lens camera (any camera file vklens reads)")
    p.add_argument("--input", required=True, type=pathlib.Path, help="folder of input frames")
    p.add_argument("--output", required=True, type=pathlib.Path, help="folder for the warped frames")
    p.add_argument("--direction", default="distort", choices=["distort", "undistort", "precorrect"])
    p.add_argument("--method", default="lut", help="as the CLI's --method (default lut)")
    p.add_argument("--source-camera", help="the pinhole side's camera file (default: the camera's intrinsics)")
    p.add_argument("--workers", type=int, help="actors (default: one per GPU, else one per core)")
    p.add_argument("--address", help="a running Ray cluster to join (default: start a local one)")
    p.add_argument("--overwrite", action="store_true", help="warp frames whose output exists too")
    args = p.parse_args(argv)

    camera = vklens.Camera.load(args.camera)
    source = vklens.Camera.load(args.source_camera) if args.source_camera else None
    frames = sorted(f for f in args.input.iterdir() if f.suffix.lower() in EXTENSIONS)
    if not frames:
        p.error(f"--input {args.input}: no frames ({', '.join(sorted(EXTENSIONS))})")
    args.output.mkdir(parents=True, exist_ok=True)
    todo = [(f, args.output / f.name) for f in frames if args.overwrite or not (args.output / f.name).exists()]

    if args.address:
        ray.init(address=args.address, include_dashboard=False, log_to_driver=False)
    else:
        ray.init(num_cpus=args.workers or os.cpu_count(), include_dashboard=False, log_to_driver=False)
    gpus = int(ray.cluster_resources().get("GPU", 0))
    workers = args.workers or gpus or int(ray.cluster_resources().get("CPU", 1))
    resources = {"num_gpus": 1} if gpus and workers <= gpus else {"num_cpus": 1}
    options = dict(direction=args.direction, method=args.method, source_camera=source)
    actors = [WarpActor.options(**resources).remote(camera, dict(options)) for _ in range(workers)]
    pool = ray.util.ActorPool(actors)

    start = time.perf_counter()
    done = 0
    for _ in pool.map_unordered(lambda a, job: a.warp.remote(str(job[0]), str(job[1])), todo):
        done += 1
        print(f"\r{done}/{len(todo)} frames", end="", file=sys.stderr, flush=True)
    devices = ray.get([a.finish.remote() for a in actors])
    seconds = time.perf_counter() - start
    print(file=sys.stderr)
    print(f"warped {done} frame(s) ({len(frames) - len(todo)} skipped) into {args.output} with "
          f"{workers} worker(s) on {sorted(set(devices))} in {seconds:.1f} s")
    ray.shutdown()


if __name__ == "__main__":
    main()
