"""The ``streamread`` command: one subcommand per use.

A user mistake (missing file, wrong option) ends with one line ``streamread: error: ...``
and exit status 2; anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from streamread.argtypes import at_least_one
from streamread.errors import InputError, StreamreadError, expected


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT such as 640x480, got {text!r}") from None
    if w < 16 or h < 16 or w > 8192 or h > 8192:
        raise argparse.ArgumentTypeError(f"expected a size between 16x16 and 8192x8192, got {text!r}")
    return w, h


def _positive(kind: type) -> object:
    def parse(text: str) -> float:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
        if value <= 0:
            raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
        return value
    return parse


def _progress(label: str) -> object:
    start = time.monotonic()

    def report(done: int, total: int) -> None:
        if done == total or done % 25 == 0:
            rate = done / max(time.monotonic() - start, 1e-6)
            left = (total - done) / max(rate, 1e-6)
            end = "\n" if done == total else ""
            print(f"\r{label}: {done}/{total} frames, {rate:.1f} frames/s, {left:.0f} s left   ",
                  end=end, file=sys.stderr, flush=True)
    return report


# ----------------------------------------------------------------------------- synth

def _cmd_synth(args: argparse.Namespace) -> int:
    from streamread.synth import sample_scene
    from streamread.synth.samples import SAMPLES, make_sample, video_params
    from streamread.synth.sheet import write_contact_sheet
    from streamread.synth.video import script, write_recording

    if args.contact_sheet:
        path = write_contact_sheet(Path(args.contact_sheet), count=args.count or 24, seed=args.seed,
                                   columns=args.columns, apparatus=args.apparatus)
        print(f"wrote {path} ({args.count or 24} renders, seeds {args.seed}..{args.seed + (args.count or 24) - 1})")
        return 0
    if args.stills:
        return _write_stills(Path(args.stills), args.count or 10, args.seed, args.apparatus, args.size)
    if args.video:
        params = video_params(sample_scene(args.seed, args.apparatus, frame_wh=args.size or (640, 480)))
        frames = script(args.protocol, params, args.fps, seed=args.seed)
        video = Path(args.video)
        csv_path, _ = write_recording(params, frames, video, args.fps,
                                      meta={"protocol": args.protocol, "seed": args.seed},
                                      progress=_progress(video.name))  # type: ignore[arg-type]
        print(f"wrote {video} and {csv_path} ({len(frames)} frames, {params.apparatus}, {args.protocol})")
        return 0
    if args.recordings:
        out = Path(args.recordings)
        chosen = [s for s in SAMPLES if not args.only or s.name in args.only]
        if args.only and len(chosen) != len(set(args.only)):
            known = ", ".join(s.name for s in SAMPLES)
            raise InputError(expected("--only", ",".join(args.only), f"names among {known}", "an unknown name"))
        for sample in chosen:
            video = make_sample(sample, out, progress=_progress(sample.name))  # type: ignore[arg-type]
            print(f"wrote {video} ({video.stat().st_size / 1e6:.2f} MB)")
        return 0
    raise InputError("synth: expected one of --contact-sheet FILE, --stills DIR, --video FILE, --recordings DIR")


def _write_stills(out: Path, count: int, seed: int, apparatus: str | None, size: tuple[int, int] | None) -> int:
    import cv2

    from streamread.synth import render_still

    out.mkdir(parents=True, exist_ok=True)
    for s in range(seed, seed + count):
        image, truth = render_still(s, apparatus, frame_wh=size)
        cv2.imwrite(str(out / f"still_{s:05d}.png"), image)
        (out / f"still_{s:05d}.json").write_text(json.dumps(truth.to_dict()))
    print(f"wrote {count} stills with truth JSON to {out}")
    return 0


# ----------------------------------------------------------------------------- inspect

def _cmd_inspect(args: argparse.Namespace) -> int:
    """Decode a recording and summarise it against its ground truth (the main job until `analyze`)."""
    import cv2

    from streamread.synth.video import read_truth_csv

    video = Path(args.video)
    if not video.is_file():
        raise InputError(expected("video", video, "an existing video file", "no such file"))
    cap = cv2.VideoCapture(str(video))
    if not cap.isOpened():
        raise InputError(expected("video", video, "a video OpenCV can decode (mp4, avi, mkv)", "a file it cannot open"))
    fps = cap.get(cv2.CAP_PROP_FPS) or 0.0
    count, size = 0, None
    start = time.perf_counter()
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        size = frame.shape[1::-1]
        count += 1
    decode_s = time.perf_counter() - start
    cap.release()
    if count == 0:
        raise InputError(expected("video", video, "at least one decodable frame", "none"))
    print(f"{video}: {count} frames, {size[0]}x{size[1]}, {fps:.2f} fps, {count / max(fps, 1e-9):.1f} s; "
          f"decoded at {count / decode_s:.0f} frames/s")
    truth_path = Path(args.truth) if args.truth else video.with_suffix(".truth.csv")
    if not truth_path.is_file():
        print(f"no ground truth beside it ({truth_path})")
        return 0
    rows = read_truth_csv(truth_path)
    if len(rows) != count:
        print(f"warning: truth has {len(rows)} rows for {count} frames")
    steps: list[tuple[str, float, int]] = []  # dwell steps: direction, level, frames
    for _, _, level, direction in rows:
        if steps and steps[-1][0] == direction and abs(steps[-1][1] - level) < 1e-9:
            steps[-1] = (direction, level, steps[-1][2] + 1)
        else:
            steps.append((direction, level, 1))
    dwells = [s for s in steps if s[2] >= 3]
    print(f"truth {truth_path}: levels {min(r[2] for r in rows):g} to {max(r[2] for r in rows):g} ml")
    for direction in ("aspirating", "dispensing", "still"):
        n = sum(1 for r in rows if r[3] == direction)
        levels = [f"{s[1]:g}" for s in dwells if s[0] == direction]
        if n:
            print(f"  {direction:<10} {n:>5} frames; dwell steps ({len(levels)}): {' '.join(levels) or '-'}")
    return 0


# ----------------------------------------------------------------------------- read

MAX_SIDE_PX = 12000


def load_image(path: Path) -> np.ndarray:
    """An image file as BGR, or an InputError that names it and says what was expected."""
    import cv2

    if not path.is_file():
        raise InputError(expected("image", path, "an existing image file", "no such file"))
    data = np.fromfile(str(path), dtype=np.uint8)
    if data.size == 0:
        raise InputError(expected("image", path, "an image (PNG, JPEG, BMP, TIFF)", "an empty file"))
    try:  # a cheap look at the size before decoding a possibly huge image
        header = cv2.imdecode(data, cv2.IMREAD_REDUCED_GRAYSCALE_8)
    except cv2.error:
        header = None
    if header is not None and max(header.shape) * 8 > MAX_SIDE_PX + 8:
        raise InputError(expected("image", path, f"at most {MAX_SIDE_PX} pixels a side",
                                  f"about {header.shape[1] * 8}x{header.shape[0] * 8}"))
    image = cv2.imdecode(data, cv2.IMREAD_COLOR)
    if image is None:
        raise InputError(expected("image", path, "an image OpenCV can decode (PNG, JPEG, BMP, TIFF)",
                                  "data it cannot decode"))
    from streamread.reader import check_image

    return check_image(image, str(path))


def _cmd_read(args: argparse.Namespace) -> int:
    import cv2

    from streamread.overlay import draw_overlay
    from streamread.profile import load_profile
    from streamread.reader import ReaderOptions, read_image
    from streamread.types import Reading

    profile = load_profile(args.profile) if args.profile else None
    options = ReaderOptions(apparatus=args.apparatus, profile=profile, detector=_detector(args))  # type: ignore[arg-type]
    overlay_dir = Path(args.overlay) if args.overlay else None
    if overlay_dir is not None:
        overlay_dir.mkdir(parents=True, exist_ok=True)
    all_read = True
    for name in args.images:
        path = Path(name)
        image = None
        try:
            image = load_image(path)
            reading = read_image(image, options)
        except InputError as exc:
            reading = Reading(level=None, sigma=None, apparatus=args.apparatus, error=str(exc))
        all_read &= reading.level is not None
        if args.json:
            print(json.dumps(reading.to_json(name)), flush=True)
        elif reading.level is not None:
            n = len(reading.calibration.marks) if reading.calibration else 0
            print(f"{name}: {reading.level:.4g} {reading.unit} +- {reading.sigma:.2g} ({reading.apparatus}, {n} marks)")
        else:
            print(f"{name}: no reading ({reading.error})")
        if overlay_dir is not None and image is not None:
            cv2.imwrite(str(overlay_dir / (path.stem + ".overlay.png")), draw_overlay(image, reading))
    return 0 if all_read else 1


# ----------------------------------------------------------------------------- analyze / watch

def _detector(args: argparse.Namespace) -> object:
    """The apparatus detector the options ask for: a model file, the bundled one, or none."""
    from streamread.detector import OnnxDetector, bundled_model_path

    choice = getattr(args, "detector", "bundled")
    if choice == "none":
        return None
    if choice == "bundled":
        return OnnxDetector() if bundled_model_path().is_file() else None
    return OnnxDetector(choice)


def _stream_config(args: argparse.Namespace) -> object:
    from streamread.profile import load_profile
    from streamread.stream import StreamConfig

    profile = load_profile(args.profile) if args.profile else None
    return StreamConfig(apparatus=args.apparatus, profile=profile, detector=_detector(args),  # type: ignore[arg-type]
                        keep_history=bool(getattr(args, "smooth", False)))


def _run_stream(args: argparse.Namespace, source: object, csv_path: Path, label: str) -> int:
    from streamread.calibfile import load_calibration
    from streamread.run import progress_bar, run_loop
    from streamread.stream import StreamReader

    config = _stream_config(args)
    loaded = None
    cal_path = Path(args.calibration) if args.calibration else None
    if cal_path is not None and cal_path.exists():
        loaded = load_calibration(cal_path, config.reader_options().forced_kind)  # type: ignore[attr-defined]
    reader = StreamReader(config, calibration=loaded)  # type: ignore[arg-type]
    recording = sink = None
    if _wants_rerun(args):
        from streamread.sink import RerunSink, open_recording

        recording = open_recording(args)
        if recording is not None:
            sink = RerunSink(recording, image_every=args.log_image_every)
    quiet = args.jsonl or args.quiet
    log = None if quiet else (lambda text: print(f"\r{text:<100}", file=sys.stderr, flush=True))
    try:
        summary = run_loop(source, reader, csv_path, jsonl=sys.stdout if args.jsonl else None, sink=sink,  # type: ignore[arg-type]
                           calibration_path=cal_path, smooth=bool(getattr(args, "smooth", False)),
                           progress=None if quiet else progress_bar(label), log=log)
    finally:
        if recording is not None:
            from streamread.sink import close_recording

            close_recording(args, recording)
    states = ", ".join(f"{k} {v}" for k, v in sorted(summary.states.items()))
    fps = summary.frames / max(summary.seconds, 1e-9)
    print(f"{label}: {summary.frames} frames in {summary.seconds:.1f} s ({fps:.0f} frames/s), "
          f"{summary.readings} with a level; OCR ran {summary.ocr_runs} time(s); states: {states or '-'}",
          file=sys.stderr)
    print(f"readings: {csv_path}", file=sys.stderr)
    if summary.interrupted:
        print(f"streamread: interrupted after {summary.frames} frames; readings up to there are in {csv_path}",
              file=sys.stderr)
        return 130
    return 0 if summary.readings else 1


def _wants_rerun(args: argparse.Namespace) -> bool:
    try:
        from streamread.sink import wants_rerun
    except ImportError:
        return False
    return wants_rerun(args)


def _cmd_analyze(args: argparse.Namespace) -> int:
    from streamread.sources import open_source

    if args.video.startswith("synth:") or any(ch in args.video for ch in "*?["):
        source = open_source(args.video, prefetch=True)
    else:
        from streamread.parallel import ParallelVideoSource, default_jobs

        # the Rerun sink logs every frame's pixels, which only the parent process has
        jobs = 1 if _wants_rerun(args) else (args.jobs or default_jobs())
        source = ParallelVideoSource(args.video, jobs=jobs)
    csv_path = Path(args.csv) if args.csv else Path(Path(args.video).stem.replace("*", "_") + ".readings.csv")
    code = _run_stream(args, source, csv_path, "analyze")
    truth = Path(args.truth) if args.truth else None
    if truth is None and not args.video.startswith("synth:"):
        beside = Path(args.video).with_suffix(".truth.csv")
        truth = beside if beside.is_file() else None
    if truth is not None and code in (0, 1) and not args.jsonl:
        from streamread.evaluate import evaluate, format_markdown, write_outputs

        report = evaluate(csv_path, truth)
        print(format_markdown(report))
        if args.eval_out:
            write_outputs(report, args.eval_out)
    return code


def _cmd_watch(args: argparse.Namespace) -> int:
    from streamread.sources import CameraSource

    if args.device.startswith("synth:"):  # a virtual camera: the renderer, for demos and tests
        from streamread.sources import SynthSource

        source = SynthSource(args.device.split(":", 1)[1] or "staircase", fps=args.fps or 15.0)
    else:
        source = CameraSource(args.device, size_wh=args.size, fps=args.fps, give_up_s=args.give_up)
    csv_path = Path(args.csv) if args.csv else Path(time.strftime("watch-%Y%m%d-%H%M%S.csv"))
    return _run_stream(args, source, csv_path, "watch")


def _add_detector_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--detector", default="bundled", metavar="MODEL.onnx|bundled|none",
                   help="YOLO-format ONNX apparatus detector used at calibration (default: the bundled model; "
                        "none: search the whole image)")


def _add_stream_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--apparatus", default="auto", choices=("auto", "syringe", "cylinder", "burette"),
                   help="what the camera sees (default auto)")
    p.add_argument("--profile", metavar="PATH", help="apparatus profile TOML (see calib/)")
    _add_detector_arg(p)
    p.add_argument("--csv", metavar="PATH", help="readings CSV (frame,time_s,level,level_raw,sigma,rate,state)")
    p.add_argument("--jsonl", action="store_true", help="also write each record as one JSON line to stdout")
    p.add_argument("--calibration", metavar="FILE",
                   help="load this saved calibration if it exists (no OCR at start); save each new one to it")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    try:
        from streamread.sink import add_rerun_args

        add_rerun_args(p)
    except ImportError:  # rerun-sdk missing: the loop still runs, without a viewer
        pass


# ----------------------------------------------------------------------------- main

def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="streamread", description=__doc__.splitlines()[0] if __doc__ else None)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    synth = sub.add_parser("synth", help="render synthetic scenes, videos and the sample recordings",
                           description="Render photographic synthetic apparatus with exact ground truth.")
    what = synth.add_mutually_exclusive_group(required=True)
    what.add_argument("--contact-sheet", metavar="FILE.png", help="a grid of random renders")
    what.add_argument("--stills", metavar="DIR", help="random stills (PNG) with truth JSON")
    what.add_argument("--video", metavar="FILE.mp4", help="a scripted recording with truth CSV and JSON")
    what.add_argument("--recordings", metavar="DIR", help="remake the bundled sample recordings")
    synth.add_argument("--seed", type=int, default=0, help="first seed (default 0)")
    synth.add_argument("--count", type=_positive(int), help="number of renders (sheet 24, stills 10)")
    synth.add_argument("--columns", type=_positive(int), default=6, help="contact sheet columns (default 6)")
    synth.add_argument("--apparatus", help="catalogue name (syringe_5ml, ...) or kind (syringe, measuring_cylinder, "
                                           "burette); default any")
    synth.add_argument("--size", type=_size, help="frame size WIDTHxHEIGHT (default: random for stills, 640x480 video)")
    synth.add_argument("--protocol", default="staircase",
                       help="video protocol: staircase, ramp, occlusion, bump, leave (default staircase)")
    synth.add_argument("--fps", type=_positive(float), default=15.0, help="video frame rate (default 15)")
    synth.add_argument("--only", nargs="+", metavar="NAME", help="with --recordings: only these samples")
    synth.set_defaults(func=_cmd_synth)

    read = sub.add_parser("read", help="read the level in still images",
                          description="Read the scale in each image: the paper's pipeline end to end.")
    read.add_argument("images", nargs="+", metavar="IMAGE", help="image files (PNG, JPEG, ...)")
    read.add_argument("--apparatus", default="auto", choices=("auto", "syringe", "cylinder", "burette"),
                      help="what the images show (default auto: burette if numbers grow downward, syringe if a "
                           "stopper is found, else cylinder)")
    read.add_argument("--profile", metavar="PATH", help="apparatus profile TOML (see calib/)")
    _add_detector_arg(read)
    read.add_argument("--json", action="store_true", help="one JSON object per image on stdout")
    read.add_argument("--overlay", metavar="DIR", help="write an annotated PNG per image here")
    read.set_defaults(func=_cmd_read)

    analyze = sub.add_parser("analyze", help="read a recorded video (or image glob, or synth:PROTOCOL) frame by frame",
                             description="Offline analysis: calibrate once, track the level in every frame, write a "
                                         "CSV (and an .rrd with --save); compare with ground truth when it is given.")
    analyze.add_argument("video", help="video file, image glob ('frames/*.png') or synth:staircase")
    _add_stream_args(analyze)
    analyze.add_argument("--smooth", action="store_true", help="RTS-smooth the level over the whole recording")
    analyze.add_argument("--jobs", type=at_least_one, metavar="N",
                         help="worker processes measuring parts of a video file (default: one per core; "
                              "files under 400 frames and runs logging to Rerun use one reader)")
    analyze.add_argument("--truth", metavar="CSV", help="ground truth (default: VIDEO.truth.csv beside it, if any)")
    analyze.add_argument("--eval-out", metavar="DIR", help="with truth: write report.json and plots here")
    analyze.set_defaults(func=_cmd_analyze)

    watch = sub.add_parser("watch", help="monitor a live V4L2 camera",
                           description="Live monitoring: read the level from a V4L2 camera until Ctrl-C.")
    watch.add_argument("device", help="/dev/videoN or a camera index (synth:PROTOCOL: the renderer as a virtual camera)")
    watch.add_argument("--size", type=_size, help="capture size WIDTHxHEIGHT")
    watch.add_argument("--fps", type=_positive(float), help="capture frame rate")
    watch.add_argument("--give-up", type=_positive(float), default=60.0, metavar="S",
                       help="stop when the camera stays gone this long (default 60 s)")
    _add_stream_args(watch)
    watch.set_defaults(func=_cmd_watch)

    from streamread.evaluate import add_eval_parser

    add_eval_parser(sub)

    inspect = sub.add_parser("inspect", help="decode a recording and summarise its ground truth")
    inspect.add_argument("video", help="video file")
    inspect.add_argument("--truth", help="ground-truth CSV (default: VIDEO.truth.csv beside it)")
    inspect.set_defaults(func=_cmd_inspect)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except StreamreadError as exc:
        print(f"streamread: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("streamread: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
