#!/usr/bin/env bash
# The resonant bench of docs/transducers.md on the virtual device: identify, drive in
# displacement mode, status, measure against predict; prints one JSON line of the figures.
# Usage: FRICCTL=target/release/fricctl scripts/resonant_bench.sh   (fricctl from PATH by default)
set -euo pipefail
F=${FRICCTL:-fricctl}
out=$(mktemp -d)
$F sim-device --pty --plant-resonance-z 20300 --plant-q-z 300 --plant-resonance-x 19700 --plant-q-x 200 --seconds 120 >"$out/pty" 2>/dev/null &
sim=$!
trap 'kill $sim 2>/dev/null; rm -rf "$out"' EXIT
for _ in $(seq 50); do [ -s "$out/pty" ] && break; sleep 0.1; done
P=$(head -1 "$out/pty")
d() { $F device --port "$P" --json "$@"; }
d drive set --freq 20000 --amp-z 0 --amp-x 0 --offset-z 4e-6 --open-loop >/dev/null
d identify >"$out/id.json"
d drive set --freq 20000 --amp-z 2e-6 --amp-x 3e-7 --offset-z 4e-6 --phase-deg 40 >/dev/null
d start >/dev/null
for _ in $(seq 100); do d status >"$out/st.json"; grep -q '"settled": true' "$out/st.json" && break; sleep 0.05; done
d measure --periods 4000 >"$out/m.json"
d predict --v0 0.004 >"$out/p.json"
python3 - "$out" <<'PY'
import json, sys, os
o = sys.argv[1]
j = lambda n: json.load(open(os.path.join(o, n)))
i, s, m, p = j("id.json"), j("st.json"), j("m.json"), j("p.json")
print(json.dumps({
  "resonance_z_hz": i["resonance_z_hz"], "q_z": i["q_z"], "resonance_x_hz": i["resonance_x_hz"], "q_x": i["q_x"],
  "identify_s": i["elapsed_s"], "settled": s["settled"],
  "amp_z_measured_m": s["amp_z_measured_m"], "amp_x_measured_m": s["amp_x_measured_m"],
  "phase_measured_deg": s["phase_measured_deg"], "amp_z_peak_m": s["amp_z_peak_m"],
  "measure_mu": m["mu"], "predict_mu": p["mu"], "measure_vs_predict_pct": 100 * (m["mu"] / p["mu"] - 1)}))
PY
