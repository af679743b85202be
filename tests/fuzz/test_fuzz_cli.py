"""Command lines with nasty option values and shapes: exit 0 or 2, one line, strict JSON."""

from __future__ import annotations

import os
import random

from fuzz_helpers import NASTY_CLI, assert_clean, n_cases, run_cli


def _commands(flightlog, model, tmp):
    """Templates: (command, {option: plausible values}).

    The non-regular output target is a FIFO made here: a fuzzer must never be able to touch a
    system file such as /dev/null (an unguarded os.replace would turn it into a regular file).
    """
    fifo = tmp / "fifo"
    if not fifo.exists():
        os.mkfifo(fifo)
    paths = [str(flightlog), str(tmp / "absent.npz"), str(tmp), str(fifo), str(model)]
    return [
        (["field", "probe"], {"--separation": ["0.36", "0.64", "-0.2"], "--radial": ["0", "0.1"],
                              "--leader-speed": ["0", "0.5"], "--samples": ["20", "2", "50"],
                              "--seed": ["0", "-1", "7"], "--model": [str(model), paths[1]]}),
        (["dock"], {"--trials": ["1"], "--offset": ["0.36", "0.5"],
                    "--leader-speed": ["0"], "--compensation":
                    ["none", "observer", "oracle", "model", "psychic"],
                    "--model": [str(model), paths[1]], "--seed": ["0", "3"]}),
        (["evaluate"], {"--model": [str(model), paths[1], str(flightlog)],
                        "--data": paths[:3], "--lateral-radius": ["0.2", "1"]}),
        (["train"], {"--data": paths[:3], "--out": [str(tmp / "t"), str(fifo), str(flightlog)],
                     "--model": ["so2", "mlp", "zero", "bogus"], "--minutes": ["0.01", "1"],
                     "--max-epochs": ["1", "2"]}),
        (["export"], {"--model": [str(model), paths[1]],
                      "--out": [str(tmp / "m.onnx"), str(tmp), str(fifo)]}),
        (["ingest"], {"--format": ["csv", "neural-swarm", "ulog", "rosbag", "pdf"],
                      "--out": [str(tmp / "i.npz"), str(tmp), str(fifo)],
                      "--mass-kg": ["0.03", "1"]}),
    ]


def _random_args(rng, templates, flightlog):
    # dock flies real trials (a second or more each): drawn less often than the others
    command, options = rng.choices(templates, weights=[3, 0.6, 2, 2, 1, 2])[0]
    args = list(command)
    if command == ["ingest"]:
        args.append(rng.choice([str(flightlog), "absent.csv"]))
    for option, values in options.items():
        if rng.random() < 0.3:
            continue
        value = rng.choice(NASTY_CLI) if rng.random() < 0.35 else rng.choice(values)
        args += [option, value]
        if option == "--data" and rng.random() < 0.3:
            args.append(rng.choice(values))  # several paths after one --data
    if rng.random() < 0.1:
        args.insert(rng.randrange(len(args) + 1), rng.choice(["--bogus", "-x", "--", "--help"]))
    if command[0] == "train":
        args += ["--max-epochs", "1"]
    args.append("--json")
    return args


def test_random_command_lines(flightlog_file, model_dir, tmp_path):
    rng = random.Random(2026)
    templates = _commands(flightlog_file, model_dir, tmp_path)
    results = [run_cli(_random_args(rng, templates, flightlog_file), family="cli-options")
               for _ in range(n_cases(100))]
    assert_clean(results)
    assert {r.rc for r in results} == {0, 2}


def test_named_cli_defects(flightlog_file, model_dir, tmp_path):
    """The command lines issue 12 lists: each refused with one line and exit code 2."""
    cases = [
        ["dock", "--leader-speed", "nan", "--trials", "1", "--json"],
        ["dock", "--offset", "inf", "--trials", "1", "--json"],
        ["dock", "--trials", "10000000", "--json"],
        ["field", "probe", "--separation", "nan", "--radial", "0", "--json"],
        ["field", "probe", "--separation", "0.36", "--radial", "0", "--samples", "100000000"],
        ["field", "probe", "--separation", "0.36", "--radial", "0", "--samples", "1e8"],
        ["dock", "--bogus"],
    ]
    for args in cases:
        res = run_cli(args, family="cli-named")
        assert_clean([res])
        assert res.rc == 2, (args, res.err)
        assert len(res.err.strip().splitlines()) == 1, res.err
    res = run_cli(["dock", "--trials", "10000000"])
    assert "10000" in res.err  # the message states the limit
    # several paths after one --data
    res = run_cli(["evaluate", "--model", model_dir, "--data", flightlog_file, flightlog_file,
                   "--json"], family="cli-named")
    assert_clean([res])
    assert res.rc == 0, res.err
