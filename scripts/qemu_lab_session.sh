#!/usr/bin/env bash
# The QEMU lab session of docs/guide/lab-session.md against the real firmware (built with
# `--features qemu`: ideal transducers, voltage mode): drive, measure, watch, a timed
# 20 000-period measure, the 7-point phase sweep, the fit, scene set --from-fit, the 2 kHz
# measure against the exact solver, the lift-off opt-in; and the same sweep on the virtual
# device (`sim-device --plant-ideal-transducers`, the same plant in f64) for the agreement of
# the rows (--plant-mu0 0.24, the QEMU plant's). Prints one JSON line of the session's noise-dependent figures.
# Usage: FRICCTL=target/release/fricctl scripts/qemu_lab_session.sh   (fricctl from PATH by default)
#        FIRMWARE_ELF=path/to/firmware to use a built ELF; else it is built as the QEMU tests
#        build it (firmware/target/qemu-tests/qemu). Five runs: scripts/qemu_lab_session.sh 5
set -euo pipefail
cd "$(dirname "$0")/.."
runs=${1:-1}
F=${FRICCTL:-fricctl}
if [ -z "${FIRMWARE_ELF:-}" ]; then
  (cd firmware && cargo build -q --release --locked --features qemu --bin firmware \
    --target-dir target/qemu-tests/qemu)
  FIRMWARE_ELF=$PWD/firmware/target/qemu-tests/qemu/thumbv7em-none-eabihf/release/firmware
fi
out=$(mktemp -d)
qemu=""
sim=""
cleanup() {
  [ -n "$qemu" ] && kill "$qemu" 2>/dev/null
  [ -n "$sim" ] && kill "$sim" 2>/dev/null
  rm -rf "$out"
}
trap cleanup EXIT
# Wall time of a command in seconds, its stdout to file $1.
timed() { local f=$1; shift; local t0; t0=$(date +%s.%N); "$@" >"$f"; echo "$(date +%s.%N) - $t0" | bc; }

one_run() {
  rm -rf "${out:?}"/*
  local port
  port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  qemu-system-arm -machine netduinoplus2 -display none -monitor none -serial null \
    -serial "tcp:127.0.0.1:$port,server=on,wait=off,nodelay=on" \
    -semihosting-config enable=on,target=native -kernel "$FIRMWARE_ELF" >/dev/null 2>&1 &
  qemu=$!
  for _ in $(seq 100); do
    (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null && break
    sleep 0.1
  done
  sleep 0.3
  d() { $F device --tcp "127.0.0.1:$port" --json "$@"; }
  d drive set --open-loop --freq 20000 --amp-z 2e-6 --amp-x 3e-7 --offset-z 4e-6 --phase-deg 40 >/dev/null
  d start >/dev/null
  d measure --periods 2000 >"$out/m1.json"
  d watch --periods 2000 --count 4 >"$out/watch.jsonl"
  # 1 s of device time at 20 kHz.
  t20k=$(timed "$out/m20k.json" d measure --periods 20000)
  tsweep=$(timed "$out/sweep.json" d sweep --param phase-deg --from 0 --to 180 --points 7 \
    --periods 300 --settle-periods 20 --v0 0.004 --csv "$out/q.csv")
  # Exit 1 is the fit's "doubtful" verdict (its residuals exceed the rows' standard errors:
  # the estimator's bias at 20 kHz, docs/guide/fit.md); the result and fit.json are written.
  $F fit --data "$out/q.csv" --params mu0 --out "$out/fit.json" --json >"$out/fitout.json" \
    || [ $? -eq 1 ]
  d measure --periods 2000 >"$out/m180.json"
  d predict --v0 0.004 >"$out/p180.json"
  d scene set --from-fit "$out/fit.json" >/dev/null
  d measure --periods 2000 >"$out/m180b.json"
  d predict --v0 0.004 >"$out/p180b.json"
  # 2 kHz, φ = 40°: the estimator's aliasing is gone; against the exact solver.
  d drive set --open-loop --freq 2000 --amp-z 2e-6 --amp-x 3e-7 --offset-z 4e-6 --phase-deg 40 >/dev/null
  d measure --periods 2000 >"$out/m2k.json"
  d config --allow-liftoff >/dev/null
  d drive set --open-loop --freq 20000 --amp-z 4e-6 --amp-x 3e-7 --offset-z 4e-6 --phase-deg 40 >/dev/null
  d predict --v0 0.004 >"$out/plift.json"
  kill "$qemu" 2>/dev/null; wait "$qemu" 2>/dev/null || true; qemu=""
  # The plant's contact (μ0 = 0.24, kz = kx = 1e7 N/m), exact solver.
  local scene=(--mu0 0.24 --kz 1e7 --kx 1e7 --uz0 4e-6 --duz 2e-6 --dux 3e-7 --phi-deg 40 --v0 0.004 --json)
  $F mu "${scene[@]}" --freq 20000 >"$out/exact20k.json"
  $F mu "${scene[@]}" --freq 2000 >"$out/exact2k.json"
  # The same sweep on the virtual device with the same (ideal-transducer) plant.
  $F sim-device --pty --plant-ideal-transducers --plant-mu0 0.24 --seconds 120 >"$out/pty" 2>/dev/null &
  sim=$!
  for _ in $(seq 50); do [ -s "$out/pty" ] && break; sleep 0.1; done
  local pty
  pty=$(head -1 "$out/pty")
  v() { $F device --port "$pty" --json "$@"; }
  v drive set --open-loop --freq 20000 --amp-z 2e-6 --amp-x 3e-7 --offset-z 4e-6 --phase-deg 40 >/dev/null
  v start >/dev/null
  v sweep --param phase-deg --from 0 --to 180 --points 7 --periods 300 --settle-periods 20 \
    --v0 0.004 --csv "$out/r.csv" >"$out/vsweep.json"
  kill "$sim" 2>/dev/null; wait "$sim" 2>/dev/null || true; sim=""
  python3 - "$out" "$t20k" "$tsweep" <<'PY'
import json, sys, os
o, t20k, tsweep = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
j = lambda n: json.load(open(os.path.join(o, n)))
m1, m180, m180b, m2k = j("m1.json"), j("m180.json"), j("m180b.json"), j("m2k.json")
p180, p180b, pl = j("p180.json"), j("p180b.json"), j("plift.json")
fit, sw, vs = j("fitout.json"), j("sweep.json"), j("vsweep.json")
e20, e2 = j("exact20k.json"), j("exact2k.json")
watch = [json.loads(l) for l in open(os.path.join(o, "watch.jsonl")) if l.strip()]
rows = sw["rows"]
vrows = vs["rows"]
print(json.dumps({
    "measure_mu": m1["mu"], "measure_std_error": m1["std_error"],
    "fx_mean_n": m1["fx_mean"], "fz_mean_n": m1["fz_mean"],
    "exact_mu_20k": e20["mu"], "measure_minus_exact_20k": m1["mu"] - e20["mu"],
    "watch_mu": [w["mu"] for w in watch], "watch_std_error": [w["std_error"] for w in watch],
    "measure_20000_periods_wall_s": t20k, "sweep_wall_s": tsweep,
    "sweep_mu": [r["measured_mu"] for r in rows], "sweep_std_error": [r["std_error"] for r in rows],
    "sweep_meas_minus_pred": [r["measured_mu"] - r["predicted_mu"] for r in rows],
    "virtual_sweep_mu": [r["measured_mu"] for r in vrows],
    "max_gap_to_virtual": max(abs(a["measured_mu"] - b["measured_mu"]) for a, b in zip(rows, vrows)),
    "fit_mu0": fit["mu0"], "fit_mu0_ci95": [fit["mu0_ci95_low"], fit["mu0_ci95_high"]],
    "fit_rms_residual": fit["rms_residual_mu"],
    "measure_180_mu": m180["mu"], "measure_180_std_error": m180["std_error"],
    "predict_180_mu": p180["mu"],
    "measure_180_after_fit_mu": m180b["mu"], "predict_180_after_fit_mu": p180b["mu"],
    "after_fit_gap": abs(m180b["mu"] - p180b["mu"]),
    "measure_2k_mu": m2k["mu"], "measure_2k_std_error": m2k["std_error"], "exact_mu_2k": e2["mu"],
    "measure_minus_exact_2k": m2k["mu"] - e2["mu"],
    "liftoff_predict_mu": pl["mu"], "liftoff_predict_mu_over_mu0": pl["mu_over_mu0"],
    "liftoff_regime": pl["regime"],
}))
PY
}

for _ in $(seq "$runs"); do one_run; done
