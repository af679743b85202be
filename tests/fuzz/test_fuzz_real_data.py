"""The shared real logs (read from ../shared/data, never copied), damaged at random, through
``aerodock ingest``: exit 0 or 2, one line, strict JSON, and an ingested file that loads."""

from __future__ import annotations

import random

from fuzz_helpers import NASTY_CLI, assert_clean, mutate_bytes, n_cases, run_cli

from aerodock.flightlog import load_flightlogs


def _mutate_csv(text: str, rng: random.Random) -> str:
    lines = text.splitlines()
    header, rows = lines[:1], lines[1:]
    for _ in range(rng.randint(1, 4)):
        roll = rng.random()
        if roll < 0.25 and rows:  # a cell replaced
            i = rng.randrange(len(rows))
            cells = rows[i].split(",")
            cells[rng.randrange(len(cells))] = rng.choice(NASTY_CLI + ["1e999", "NaN", ",,"])
            rows[i] = ",".join(cells)
        elif roll < 0.4:  # rows dropped or duplicated
            i = rng.randrange(len(rows) + 1)
            rows[i:i + rng.randint(1, 50)] = rows[i:i + rng.randint(0, 3)] * rng.randint(0, 2)
        elif roll < 0.5:  # truncated
            rows = rows[: rng.randrange(len(rows) + 1)]
        elif roll < 0.6 and header:  # header damaged
            cols = header[0].split(",")
            cols[rng.randrange(len(cols))] = rng.choice(["", "x", "time[ms]", "z[mm]"])
            header = [",".join(cols)]
        elif roll < 0.7 and rows:  # a column scaled (mm, ms, g)
            k = rng.randrange(len(rows[0].split(",")))
            scale = rng.choice([1000.0, 1e-3, -1.0, 0.0])
            out = []
            for row in rows:
                cells = row.split(",")
                try:
                    cells[k] = repr(float(cells[k]) * scale)
                except (ValueError, IndexError):
                    pass
                out.append(",".join(cells))
            rows = out
        else:
            return mutate_bytes(("\n".join(header + rows)).encode(), rng).decode("latin-1")
    return "\n".join(header + rows) + "\n"


def test_damaged_neural_swarm_flights(shared_data, tmp_path):
    folder = shared_data("neural-swarm", "swap_ss")
    pairs = [(folder / f"cf50_0{k}.csv", folder / f"cf51_0{k}.csv") for k in range(2)]
    texts = [(a.read_text(), b.read_text()) for a, b in pairs]
    rng = random.Random(11)
    results = []
    for i in range(n_cases(15)):
        a_text, b_text = rng.choice(texts)
        (tmp_path / "cf50_00.csv").write_text(_mutate_csv(a_text, rng) if i % 2 else a_text)
        (tmp_path / "cf51_00.csv").write_text(_mutate_csv(b_text, rng))
        out = tmp_path / "out.npz"
        res = run_cli(["ingest", "--format", "neural-swarm", tmp_path / "cf50_00.csv",
                       tmp_path / "cf51_00.csv", "--out", out, "--json"], family="ingest-real")
        results.append(res)
        if res.rc == 0:
            assert load_flightlogs(out)
    assert_clean(results)


def test_damaged_ulog(shared_data, tmp_path):
    blob = shared_data("px4-ulog", "sample_log_small.ulg").read_bytes()
    rng = random.Random(12)
    results = []
    for _ in range(n_cases(15)):
        path = tmp_path / "log.ulg"
        path.write_bytes(mutate_bytes(blob, rng))
        results.append(run_cli(["ingest", "--format", "ulog", "--single", path, "--out",
                                tmp_path / "u.npz", "--json"], family="ingest-real"))
    assert_clean(results)
