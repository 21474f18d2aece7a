#!/usr/bin/env bash
# The tracking scenario of docs/transducers.md ("Resonance tracking") on the virtual device:
# a normal resonance drifting -20 Hz/s, identify, drive with --track z, start, 5 s, then
# status, measure and predict; prints one JSON line of the figures.
# Usage: scripts/tracking_session.sh [N]   (N runs, default 1; fricctl from target/release)
set -euo pipefail
F=${FRICCTL:-target/release/fricctl}
runs=${1:-1}
for run in $(seq "$runs"); do
  out=$(mktemp -d)
  $F sim-device --pty --plant-resonance-z 20100 --plant-q-z 300 --plant-resonance-x 19700 \
    --plant-q-x 200 --plant-resonance-drift-z -20 --seconds 300 >"$out/pty" 2>/dev/null &
  sim=$!
  for _ in $(seq 50); do [ -s "$out/pty" ] && break; sleep 0.1; done
  port=$(head -n1 "$out/pty" | grep -o '/dev/[^ ]*')
  d() { $F device --port "$port" --json "$@"; }
  d drive set --freq 20100 --amp-z 0 --amp-x 0 --offset-z 4e-6 --open-loop >/dev/null
  d identify >"$out/id.json"
  d drive set --freq 20100 --amp-z 2e-6 --amp-x 3e-7 --offset-z 4e-6 --phase-deg 40 --track z >/dev/null
  d start >/dev/null
  sleep 5
  d status >"$out/st.json"
  d measure --periods 4000 >"$out/m.json"
  d predict --v0 0.004 >"$out/p.json"
  d status >"$out/st2.json"
  kill "$sim" 2>/dev/null || true
  wait "$sim" 2>/dev/null || true
  python3 - "$out" "$run" <<'PY'
import json, sys
o, run = sys.argv[1], int(sys.argv[2])
l = lambda n: json.load(open(f"{o}/{n}.json"))
i, s, m, p, s2 = l("id"), l("st"), l("m"), l("p"), l("st2")
print(json.dumps({"run": run, "identified_z_hz": i.get("resonance_z_hz"),
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
