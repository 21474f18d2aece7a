#!/usr/bin/env bash
# The tracking scenario of the README and docs/transducers.md ("Resonance tracking") on the
# virtual device: a normal resonance drifting DRIFT Hz/s from the moment sim-device starts,
# identify, drive with --track z, start, 5 s, then status, measure and predict; prints one
# JSON line of the figures, with the seconds from sim-device's start to the last status.
# PAUSE seconds between the commands stand for a person typing them (README: DRIFT=-2
# PAUSE=10; docs/transducers.md: DRIFT=-20 PAUSE=0, which only a script meets: the drive
# leaves the ±2 % tracking range 22 s after sim-device starts).
# Usage: [DRIFT=-20] [PAUSE=0] scripts/tracking_session.sh [N]   (N runs, default 1;
# fricctl from target/release, or FRICCTL)
set -euo pipefail
F=${FRICCTL:-target/release/fricctl}
DRIFT=${DRIFT:--20}
PAUSE=${PAUSE:-0}
runs=${1:-1}
for run in $(seq "$runs"); do
  out=$(mktemp -d)
  $F sim-device --pty --plant-resonance-z 20100 --plant-q-z 300 --plant-resonance-x 19700 \
    --plant-q-x 200 --plant-resonance-drift-z "$DRIFT" --seconds 600 >"$out/pty" 2>/dev/null &
  sim=$!
  t0=$(date +%s.%N)
  for _ in $(seq 50); do [ -s "$out/pty" ] && break; sleep 0.1; done
  port=$(head -n1 "$out/pty" | grep -o '/dev/[^ ]*')
  d() { $F device --port "$port" --json "$@"; }
  d drive set --freq 20100 --amp-z 0 --amp-x 0 --offset-z 4e-6 --open-loop >/dev/null
  sleep "$PAUSE"
  d identify >"$out/id.json"
  sleep "$PAUSE"
  d drive set --freq 20100 --amp-z 2e-6 --amp-x 3e-7 --offset-z 4e-6 --phase-deg 40 --track z >/dev/null
  sleep "$PAUSE"
  d start >/dev/null
  sleep 5
  d status >"$out/st.json"
  sleep "$PAUSE"
  d measure --periods 4000 >"$out/m.json"
  sleep "$PAUSE"
  d predict --v0 0.004 >"$out/p.json"
  sleep "$PAUSE"
  d status >"$out/st2.json"
  t1=$(date +%s.%N)
  kill "$sim" 2>/dev/null || true
  wait "$sim" 2>/dev/null || true
  python3 - "$out" "$run" "$t0" "$t1" "$DRIFT" <<'PY'
import json, sys
o, run = sys.argv[1], int(sys.argv[2])
elapsed_s, drift = float(sys.argv[4]) - float(sys.argv[3]), float(sys.argv[5])
l = lambda n: json.load(open(f"{o}/{n}.json"))
i, s, m, p, s2 = l("id"), l("st"), l("m"), l("p"), l("st2")
print(json.dumps({"run": run, "drift_hz_per_s": drift, "elapsed_s": round(elapsed_s, 1),
  "identified_z_hz": i.get("resonance_z_hz"),
  "frequency_hz": s["frequency_hz"], "locked": s["locked"],
  "tracking_error_hz": s["tracking_error_hz"],
  "tracking_error_pct": 100 * s["tracking_error_hz"] / s["frequency_hz"],
  "faults": s["faults"], "amp_z_measured_m": s["amp_z_measured_m"],
  "amp_z_peak_m": s["amp_z_peak_m"], "measure_mu": m["mu"], "predict_mu": p["mu"],
  "measure_vs_predict_pct": 100 * (m["mu"] / p["mu"] - 1),
  "locked_after_measure": s2["locked"], "faults_after_measure": s2["faults"]}))
PY
  rm -rf "$out"
done
