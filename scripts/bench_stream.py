"""Speed and accuracy of the streaming reader, measured in one run (ratios, since machines are noisy).

    uv run python scripts/bench_stream.py [VIDEO] [--apparatus syringe] [--paper-frames 10] [--minutes 10]

Reports, for one 640x480 recording:
- plain decoding (frames/s);
- the cached per-frame path alone (decoded frames held in memory; ms per frame, median and p95);
- ``analyze`` end to end (decode + per-frame path + CSV), as a ratio to plain decoding: as
  the CLI runs it (worker processes measuring parts of the file, one per core), and with one
  reader (decoding in a background thread, and in the loop);
- the paper's way (the full still pipeline, OCR included, on every frame), as a ratio;
- memory (RSS) at the start and end of a long run (the recording looped to ``--minutes``);
- the CLI's ratio on that long run written out as one file (one-off costs weigh less there);
- accuracy against the truth CSV beside the video: MAE, bias, R^2 per direction.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from streamread.evaluate import evaluate  # noqa: E402
from streamread.parallel import ParallelVideoSource, default_jobs  # noqa: E402
from streamread.reader import ReaderOptions, read_image  # noqa: E402
from streamread.run import run_loop  # noqa: E402
from streamread.sources import Frame, VideoFileSource  # noqa: E402
from streamread.stream import StreamConfig, StreamReader  # noqa: E402


def rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def plain_decode_fps(path: Path) -> float:
    """Decoding alone, frames dropped as they come (what a plain reader of the file does)."""
    cap = cv2.VideoCapture(str(path))
    n = 0
    start = time.perf_counter()
    while cap.read()[0]:
        n += 1
    return n / (time.perf_counter() - start)


def decode_fps(path: Path) -> tuple[float, list[np.ndarray]]:
    cap = cv2.VideoCapture(str(path))
    frames = []
    start = time.perf_counter()
    while True:
        ok, image = cap.read()
        if not ok:
            break
        frames.append(image)
    return len(frames) / (time.perf_counter() - start), frames


class LoopedSource:
    """The recording decoded again and again (a long run without a long file)."""

    def __init__(self, path: Path, total: int) -> None:
        self.path, self.frame_count, self.name = path, total, "looped"
        self.fps = VideoFileSource(path).fps

    def __iter__(self):  # type: ignore[no-untyped-def]
        i = 0
        while i < self.frame_count:
            for item in VideoFileSource(self.path):
                if isinstance(item, Frame):
                    yield Frame(i, i / self.fps, item.image)
                    i += 1
                    if i >= self.frame_count:
                        return

    def close(self) -> None:
        pass


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("video", nargs="?", default=str(ROOT / "recordings" / "syringe5ml_staircase.mp4"))
    parser.add_argument("--apparatus", default="syringe")
    parser.add_argument("--paper-frames", type=int, default=10)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--no-rerun", dest="rerun", action="store_false", help="skip the Rerun logging runs")
    parser.add_argument("--rounds", type=int, default=7, help="interleaved decode/analyze rounds for the ratios")
    parser.add_argument("--long-rounds", type=int, default=3,
                        help="rounds of the ratio on the looped recording written out as one long file (0: skip)")
    args = parser.parse_args()
    video = Path(args.video)
    config = StreamConfig(apparatus=args.apparatus)

    _, frames = decode_fps(video)
    fps_decode = 0.0
    fps_decode = max(fps_decode, plain_decode_fps(video), plain_decode_fps(video))
    print(f"video {video.name}: {len(frames)} frames {frames[0].shape[1]}x{frames[0].shape[0]}")
    print(f"plain decoding: {fps_decode:.0f} frames/s ({1000 / fps_decode:.2f} ms/frame)")

    reader = StreamReader(config)
    first = reader.process(Frame(0, 0.0, frames[0]))
    calib_s = first.timings_s.get("calibrate", float("nan"))
    per_frame = []
    for i, image in enumerate(frames[1:], start=1):
        t = time.perf_counter()
        reader.process(Frame(i, i / 15.0, image))
        per_frame.append(time.perf_counter() - t)
    ms = sorted(1000 * x for x in per_frame)
    print(f"calibration (OCR) on frame 0: {calib_s:.2f} s")
    print(f"cached per-frame path (no decode): median {statistics.median(ms):.3f} ms, "
          f"p95 {ms[int(0.95 * len(ms))]:.3f} ms, OCR re-runs {reader.ocr_runs - 1}")

    # the decoded frames (some 800 MB) are not kept through the end-to-end runs: a process that
    # holds them forks and pages slower than the CLI does
    frames = frames[: args.paper_frames]
    with tempfile.TemporaryDirectory() as tmp:
        # this machine's speed drifts by 2x within a minute: each round times plain decoding and
        # the two analyze variants back to back, and the ratio is the median over rounds
        jobs = default_jobs()
        cli_label = f"analyze as the CLI runs ({jobs} worker process{'es' if jobs > 1 else ''})"
        ratios: dict[str, list[float]] = {cli_label: [], "analyze, one reader (decode prefetched)": [],
                                          "analyze, one reader, decode in the loop": []}
        fps_seen: dict[str, list[float]] = {k: [] for k in ratios}
        decode_seen = []
        for _ in range(args.rounds):
            plain = plain_decode_fps(video)
            decode_seen.append(plain)
            for label in ratios:
                source: object
                if label == cli_label:
                    source = ParallelVideoSource(video, jobs=jobs)
                else:
                    source = VideoFileSource(video, prefetch="prefetched" in label)
                start = time.perf_counter()
                summary = run_loop(source, StreamReader(config), Path(tmp) / "r.csv")  # type: ignore[arg-type]
                fps_an = summary.frames / (time.perf_counter() - start)
                fps_seen[label].append(fps_an)
                ratios[label].append(fps_an / plain)
        for label in ratios:
            r = sorted(ratios[label])
            print(f"{label}: median {statistics.median(fps_seen[label]):.0f} frames/s = "
                  f"{statistics.median(r):.2f} x plain decoding (rounds: {r[0]:.2f}-{r[-1]:.2f}; "
                  f"incl. one calibration per run; plain decoding {min(decode_seen):.0f}-{max(decode_seen):.0f} frames/s)")
        fps_an = statistics.median(fps_seen[cli_label])
        fps_one = statistics.median(fps_seen["analyze, one reader (decode prefetched)"])
        truth_path = video.with_suffix(".truth.csv")
        report = evaluate(Path(tmp) / "r.csv", truth_path) if truth_path.is_file() else None
        if args.rerun:
            import rerun as rr

            from streamread.sink import RerunSink

            for every in (1, 10):
                rec = rr.RecordingStream("streamread_bench")
                rec.save(Path(tmp) / f"r{every}.rrd")
                start = time.perf_counter()
                summary = run_loop(VideoFileSource(video, prefetch=True), StreamReader(config), Path(tmp) / "s.csv",
                                   sink=RerunSink(rec, image_every=every))
                rec.disconnect()
                fps_sink = summary.frames / (time.perf_counter() - start)
                print(f"analyze with Rerun logging (.rrd, image every {every} frame(s)): {fps_sink:.0f} frames/s = "
                      f"{fps_sink / fps_one:.2f} x one reader without logging")

    n = args.paper_frames
    start = time.perf_counter()
    for image in frames[:n]:
        read_image(image, ReaderOptions(apparatus=args.apparatus))
    fps_paper = n / (time.perf_counter() - start)
    print(f"paper's way (full pipeline with OCR every frame, {n} frames): {fps_paper:.2f} frames/s; "
          f"ours is {fps_an / fps_paper:.0f} x faster")

    if report is not None:  # the last analyze run against the truth beside the video
        for direction in ("aspirating", "dispensing"):
            m = report.per_frame[direction]
            if not m.n:
                continue
            print(f"{direction}: n {m.n}, MAE {m.mae:.4f} ml, bias {m.bias:+.4f} ml, "
                  f"max {m.max_abs:.3f} ml, R^2 {m.r2:.5f}")

    del frames
    total = int(args.minutes * 60 * 15)
    with tempfile.TemporaryDirectory() as tmp:
        reader = StreamReader(config)
        source = LoopedSource(video, total)
        marks = []
        checkpoints = {500, total // 4, total // 2, 3 * total // 4, total}

        def progress(done: int, _total: int | None, _elapsed: float, _result: object) -> None:
            if done in checkpoints:
                marks.append((done, rss_mb()))
        summary = run_loop(source, reader, Path(tmp) / "long.csv", progress=progress)  # type: ignore[arg-type]
    print(f"memory over {args.minutes:g} min of video ({total} frames, {summary.ocr_runs} OCR runs): " +
          ", ".join(f"frame {d}: {mb:.1f} MB" for d, mb in marks))
    if args.long_rounds:
        long_file_ratio(video, total, config, args.long_rounds)
    return 0


def long_file_ratio(video: Path, total: int, config: StreamConfig, rounds: int) -> None:
    """The CLI's ratio on a long file (the recording looped and written out): the one-off
    costs of a run (calibration, starting the workers) weigh less than on a one-minute file."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "long.mp4"
        looped = LoopedSource(video, total)
        writer = None
        for item in looped:
            if writer is None:
                h, w = item.image.shape[:2]
                writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), looped.fps, (w, h))
            writer.write(item.image)
        assert writer is not None
        writer.release()
        ratios, plains, ours = [], [], []
        for _ in range(rounds):
            plain = plain_decode_fps(path)
            start = time.perf_counter()
            summary = run_loop(ParallelVideoSource(path, jobs=default_jobs()), StreamReader(config),  # type: ignore[arg-type]
                               Path(tmp) / "long.csv")
            fps = summary.frames / (time.perf_counter() - start)
            ratios.append(fps / plain)
            plains.append(plain)
            ours.append(fps)
        r = sorted(ratios)
        print(f"analyze as the CLI runs, on the recording looped to {total} frames and written out: median "
              f"{statistics.median(ours):.0f} frames/s = {statistics.median(r):.2f} x plain decoding (rounds: "
              f"{r[0]:.2f}-{r[-1]:.2f}; plain decoding of that file {min(plains):.0f}-{max(plains):.0f} frames/s)")


if __name__ == "__main__":
    sys.exit(main())
