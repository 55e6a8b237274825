#!/usr/bin/env bash
# One speed experiment on the GPU machine, in one call of the device tool (carry .deps):
#   bash Utilities/gpu/probe.sh
# builds the tree (A), times 1M particles in single and double precision, runs the fast GPU tests
# and profiles the density and correction passes with ncu, source-level counters included
# ($OUT/probe.tgz: .ncu-rep, details, per-SASS-instruction CSV, summarised in the log by
# gpu/hotspots.py; the log is $OUT/probe.log; without
# $OUT both go to output/probe/, git-ignored). Options, by environment:
#   PBF_PROBE_IEEE=1        also build B: PBF_PROBE_B_FLAGS (CMake flags; default
#                           -DPBF_CUDA_IEEE_GRADIENT=ON) and/or PBF_PROBE_B_MASKS (a file that
#                           replaces Solver/Cuda/NeighborMasks.h), timed in the same session
#   PBF_PROBE_SKINS="..."   mask skins for A (default 0.002, the default); PBF_PROBE_A_ARGS: one more A run
#   PBF_PROBE_10M=1         10M particles too; PBF_PROBE_REPEAT=1: the 1M runs again
#   PBF_PROBE_TESTS=filter  gtest filter of pbf_cuda_tests, or none; PBF_PROBE_NCU=0: no ncu,
#                           PBF_PROBE_NCU=times: only the per-kernel times of one step
#   PBF_PROBE_NCU_ALL=1     the vorticity and confinement passes profiled too
#   PBF_PROBE_VARIANTS="name:FLAGS;name2:FLAGS2"   more builds of the same tree with other CMake
#                           flags (e.g. -DCMAKE_CUDA_FLAGS=-DX=1), each timed at 1M in single
#                           precision with its per-kernel times, after A
#                           (PBF_PROBE_VARIANT_F64=1: in double precision too)
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=${OUT:-$root/output/probe}
mkdir -p "$out"
exec > >(tee "$out/probe.log") 2>&1
t0=$SECONDS
configure() { # DIR EXTRA...
  local dir=$1
  shift
  cmake -S "$root" -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPBF_SOLVER_ONLY=ON \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DPBF_JSON_INCLUDE_DIR="$root/.deps/json" \
    -DPBF_GTEST_SOURCE_DIR="$root/.deps/googletest" "$@" >"$dir.configure.log" 2>&1
}
A=/tmp/probe-a
configure $A && cmake --build $A -j 16 --target pbf_bench pbf_cuda_tests >$A.build.log 2>&1 &
pa=$!
if [[ ${PBF_PROBE_IEEE:-0} == 1 ]]; then
  B=/tmp/probe-b
  srcB=$root
  if [[ -n ${PBF_PROBE_B_MASKS:-} ]]; then # B: the tree with another NeighborMasks.h
    srcB=/tmp/probe-src-b
    rm -rf $srcB && cp -r "$root" $srcB && cp "$root/$PBF_PROBE_B_MASKS" $srcB/Solver/Cuda/NeighborMasks.h
  fi
  cmake -S "$srcB" -B "$B" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPBF_SOLVER_ONLY=ON \
    -DCMAKE_CUDA_ARCHITECTURES=90 -DPBF_JSON_INCLUDE_DIR="$root/.deps/json" \
    -DPBF_GTEST_SOURCE_DIR="$root/.deps/googletest" ${PBF_PROBE_B_FLAGS:-} >"$B.configure.log" 2>&1 &&
    cmake --build $B -j 16 --target pbf_bench >$B.build.log 2>&1 &
  pb=$!
  wait $pb || { tail -30 $B.build.log; }
fi
variants=()
pids=()
IFS=';' read -ra variants <<<"${PBF_PROBE_VARIANTS:-}"
for v in "${variants[@]}"; do
  name=${v%%:*}
  # shellcheck disable=SC2086 # the flags are words
  configure /tmp/probe-$name ${v#*:} && cmake --build /tmp/probe-$name -j 16 --target pbf_bench \
    >/tmp/probe-$name.build.log 2>&1 &
  pids+=($!)
done
wait $pa || { tail -40 $A.build.log; exit 1; }
# Not a bare wait: that would also wait for the tee above, which never ends.
for p in "${pids[@]}"; do
  wait "$p" || echo "a variant failed to build (see /tmp/probe-*.build.log)"
done
grep -i "spill" $A.build.log | sed 's/_ZN3pbf4cuda[^ ]*\(Stage\)[^ ]*/<\1>/' | head
echo "[$((SECONDS - t0)) s] built"
bench() { # BUILD LABEL ARGS...
  local b=$1 label=$2
  shift 2
  echo "== $label: $*"
  timeout 60 "$b/Solver/Tools/pbf_bench" --backend cuda "$@" 2>&1 | tail -n 2
}
for skin in ${PBF_PROBE_SKINS:-0.002}; do
  bench $A "A f32 skin $skin" --particles 1000000 --warmup 20 --steps 100 --skin "$skin"
done
bench $A "A f64" --precision double --particles 1000000 --warmup 20 --steps 100
[[ -n ${B:-} ]] && bench $B "B f32" --particles 1000000 --warmup 20 --steps 100
[[ -n ${B:-} && ${PBF_PROBE_B_F64:-1} == 1 ]] && bench $B "B f64" --precision double --particles 1000000 --warmup 20 --steps 100
[[ -n ${PBF_PROBE_A_ARGS:-} ]] && bench $A "A f32 $PBF_PROBE_A_ARGS" --particles 1000000 --warmup 20 --steps 100 $PBF_PROBE_A_ARGS
[[ ${PBF_PROBE_10M:-0} == 1 ]] && bench $A "A f32 10M" --particles 10000000 --warmup 10 --steps 50
[[ ${PBF_PROBE_10M:-0} == 1 && -n ${B:-} ]] && bench $B "B f32 10M" --particles 10000000 --warmup 10 --steps 50
[[ ${PBF_PROBE_REPEAT:-0} == 1 ]] && bench $A "A f32 again" --particles 1000000 --warmup 20 --steps 100
[[ ${PBF_PROBE_REPEAT:-0} == 1 && -n ${B:-} ]] && bench $B "B f32 again" --particles 1000000 --warmup 20 --steps 100
for v in "${variants[@]}"; do
  bench /tmp/probe-${v%%:*} "${v%%:*} f32" --particles 1000000 --warmup 20 --steps 100
  [[ ${PBF_PROBE_VARIANT_F64:-0} == 1 ]] &&
    bench /tmp/probe-${v%%:*} "${v%%:*} f64" --precision double --particles 1000000 --warmup 20 --steps 100
done
[[ ${#variants[@]} -gt 0 ]] && bench $A "A f32 again" --particles 1000000 --warmup 20 --steps 100
[[ ${#variants[@]} -gt 0 && ${PBF_PROBE_VARIANT_F64:-0} == 1 ]] &&
  bench $A "A f64 again" --precision double --particles 1000000 --warmup 20 --steps 100
echo "[$((SECONDS - t0)) s] benched"
[[ ${PBF_PROBE_TESTS:-} != none ]] && timeout 150 $A/Testing/Cuda/pbf_cuda_tests --gtest_filter="${PBF_PROBE_TESTS:-*OneStep*:*TwoRuns*:*NeighborMasks*:*Statistics*}" 2>&1 |
  grep -E "^\[ +(OK|FAILED|PASSED|SKIPPED) |Failure|Expected|Which is|actual|error" | head -40
echo "[$((SECONDS - t0)) s] tested"
if [[ ${PBF_PROBE_NCU:-1} != 0 ]]; then
  prof() { # NAME REGEX SKIP
    timeout 90 ncu --clock-control none --kernel-name-base demangled -k "regex:$2" --launch-skip "$3" \
      --launch-count 1 --section SpeedOfLight --section SchedulerStats --section WarpStateStats \
      --section Occupancy --section SourceCounters --section InstructionStats \
      --metrics smsp__thread_inst_executed_per_inst_executed.ratio,smsp__inst_executed.sum \
      -o "/tmp/$1" -f $A/Solver/Tools/pbf_bench --backend cuda --particles 1000000 --warmup 60 \
      --steps 1 >/tmp/$1.ncu.log 2>&1
    ncu -i "/tmp/$1.ncu-rep" --page details >"/tmp/$1.details.txt" 2>&1
    ncu -i "/tmp/$1.ncu-rep" --page source --csv --print-source sass >"/tmp/$1.sass.csv" 2>&1
    python3 "$root/Utilities/gpu/hotspots.py" "/tmp/$1.sass.csv" --top 12 | head -16
    grep -E "Duration|Issue Slots Busy|Executed Ipc A|Registers Per|Achieved Occupancy|No Eligible|thread_inst_executed_per|inst_executed.sum|Branch Efficiency|Avg. Divergent" "/tmp/$1.details.txt" | head -14
  }
  if [[ ${PBF_PROBE_NCU:-1} != times ]]; then
    echo "== ncu density (iteration 1)"; prof density DensityStage 242
    echo "== ncu correction (iteration 1)"; prof correction CorrectionStage 241
  fi
  if [[ ${PBF_PROBE_NCU_ALL:-0} == 1 ]]; then
    echo "== ncu vorticity"; prof vorticity VorticityStage 60
    echo "== ncu confinement"; prof confinement ConfinementStage 60
  fi
  kernelTimes() { # BUILD: per-kernel times of one step at 1M
    timeout 60 ncu --clock-control none --metrics gpu__time_duration.sum --csv --page raw \
      --launch-skip $((13 + 60 * 22)) --launch-count 22 \
      $1/Solver/Tools/pbf_bench --backend cuda --particles 1000000 --warmup 60 --steps 1 >/tmp/times.csv 2>&1
    python3 - /tmp/times.csv <<'PY' || true
import csv, sys, re
rows = [r for r in csv.reader(open(sys.argv[1])) if len(r) > 5]
# pbf_bench prints its own lines before ncu's CSV: the header is the row that names the kernels.
rows = rows[next(k for k, r in enumerate(rows) if "Kernel Name" in r):]
head = rows[0]
ki, ti = head.index("Kernel Name"), head.index("gpu__time_duration.sum")
total = 0
for r in rows[2:]:
    name = r[ki]
    m = re.search(r"(\w+Stage)", name)
    t = float(r[ti].replace(",", "")) / 1000.0  # ncu groups thousands with commas
    total += t
    print("%9.1f us  %s" % (t, m.group(1) if m else name[:60]))
print("%9.1f us  total" % total)
PY
  }
  echo "== per-kernel times, A"; kernelTimes $A
  for v in "${variants[@]}"; do
    echo "== per-kernel times, ${v%%:*}"; kernelTimes /tmp/probe-${v%%:*}
  done
fi
(cd /tmp && tar czf "$out/probe.tgz" ./*.ncu-rep ./*.details.txt ./*.sass.csv ./*.ncu.log ./times.csv \
  ./probe-a.build.log 2>/dev/null)
echo "[$((SECONDS - t0)) s] done"
