#!/usr/bin/env bash
# Decomposed runs on GPUs, in one call of the device tool (carry [".deps"], made here by
# Utilities/gpu/deps.sh):
#   1. build Solver/ with CUDA (sm_90) and MPI, and its tests, without ParaView (all cores)
#   2. the CUDA sub-domain tests (CudaSubdomain.*), the 1-2-3-rank 10-step test under
#      compute-sanitizer memcheck and the float 1-step test under racecheck (--sanitize), then the
#      gpu-labelled ctest (capped, before the scaling; without --no-ctest)
#   3. pbf_bench_mpi --backend cuda, one rank per GPU (its local rank's): strong scaling at P
#      particles (default 32M) and weak scaling at Q per GPU (default 16M) on 1, 2, 4 GPUs (counts
#      the machine lacks are skipped), and pbf_bench's single-GPU DeviceStepper at Q and P, the
#      reference a decomposed run has to beat; strong 4 GPUs once more (the run-to-run spread)
# Every phase has a time limit inside PBF_GPU_BUDGET seconds (default 560), so the short table
# comes last within the device tool's 10 minutes. Logs and JSON go under $OUT (else
# output/gpu-scaling). Options: --particles P --per-gpu Q --steps S --no-ctest --sanitize --quick
# (--quick: no CudaStepper references; strong 1, 2 and 4 GPUs, strong 4 twice, and weak 1 and 4)
# --ab "VAR=VALUE[ VAR=VALUE...]" (repeatable, with --quick): extra rows of strong 4 with the
# given environment (an experiment's switch), each run after strong 4 and again after its repeat.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=${OUT:-$root/output/gpu-scaling}
build=${PBF_GPU_BUILD:-/tmp/pbf-gpu-scaling-build}
budget=${PBF_GPU_BUDGET:-560}
particles=32000000
per_gpu=16000000
steps=20
ctest_all=1
sanitize=0
quick=0
ab=()
while (($#)); do
  case $1 in
    --particles) particles=$2; shift 2 ;;
    --per-gpu) per_gpu=$2; shift 2 ;;
    --steps) steps=$2; shift 2 ;;
    --no-ctest) ctest_all=0; shift ;;
    --sanitize) sanitize=1; shift ;;
    --quick) quick=1; shift ;;
    --ab) ab+=("$2"); shift 2 ;;
    *) sed -n '2,22p' "$0"; exit 2 ;;
  esac
done
mkdir -p "$out"
exec > >(tee "$out/gpu-scaling.log") 2>&1
t0=$SECONDS
phase() { echo; echo "== [$((SECONDS - t0)) s] $*"; }
# limit SECONDS: the phase's own limit, cut to what the budget has left (40 s kept for the end).
limit() {
  local left=$((budget - 40 - (SECONDS - t0)))
  ((left < $1)) && echo $((left > 5 ? left : 5)) || echo "$1"
}

phase "machine"
nvidia-smi --query-gpu=index,name,driver_version,memory.total,clocks.max.sm --format=csv 2>&1 || true
nvidia-smi topo -m 2>/dev/null | head -8 || true
gpus=$(nvidia-smi -L 2>/dev/null | grep -c '^GPU' || echo 0)
echo "GPUs: $gpus; cores: $(nproc); $(nvcc --version | tail -1); $(cmake --version | head -1)"
echo "mpiexec: $(command -v mpiexec) $(mpiexec --version 2>&1 | head -1)"
echo "commit: $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"

phase "build"
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if timeout "$(limit 300)" cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
    -DPBF_SOLVER_ONLY=ON -DBUILD_TESTING=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DPBF_JSON_INCLUDE_DIR="$root/.deps/json" -DPBF_GTEST_SOURCE_DIR="$root/.deps/googletest" \
    >"$out/configure.log" 2>&1 &&
  timeout "$(limit 300)" cmake --build "$build" -j "$(nproc)" >"$out/build.log" 2>&1; then
  echo "build: ok"
else
  tail -n 40 "$out/configure.log" "$out/build.log"
  echo "build: FAILED"
  exit 1
fi
bench_mpi=$build/Solver/Tools/pbf_bench_mpi
bench=$build/Solver/Tools/pbf_bench
[[ -x $bench_mpi ]] || { echo "pbf_bench_mpi was not built (no MPI found?)"; exit 1; }

phase "the decomposed CUDA stepper's tests (CudaSubdomain.*, ranks as threads on GPU 0)"
subdomain=$build/Testing/Cuda/pbf_cuda_subdomain_tests
timeout "$(limit 150)" "$subdomain" 2>&1 | grep -vE "^\[ RUN|^Running main|^\[-|^$" | tail -30
if ((PIPESTATUS[0] != 0)) && command -v gdb >/dev/null; then
  phase "a failed or crashed test under gdb"
  timeout "$(limit 60)" gdb -batch -ex run -ex bt --args "$subdomain" --gtest_filter='*OneTwoAndThree*' 2>&1 |
    grep -vE "^\[New Thread|^\[Thread .* exited" | tail -30
fi

if ((sanitize)); then
  sanitizer=$(command -v compute-sanitizer || ls /usr/local/cuda*/bin/compute-sanitizer 2>/dev/null | head -1)
  if [[ -n $sanitizer ]]; then
    phase "compute-sanitizer memcheck: CudaSubdomain 1, 2, 3 ranks, 10 steps"
    timeout "$(limit 80)" "$sanitizer" --tool memcheck --leak-check full --error-exitcode 99 \
      "$subdomain" --gtest_filter='*OneTwoAndThree*' 2>&1 | grep -vE "^\[ RUN|^Running main|^\[-|^$" | tail -12
    echo "memcheck exit: ${PIPESTATUS[0]}"
    phase "compute-sanitizer racecheck: CudaSubdomain float, 2 and 3 ranks, 1 step"
    timeout "$(limit 40)" "$sanitizer" --tool racecheck --error-exitcode 99 \
      "$subdomain" --gtest_filter='*SinglePrecision*' 2>&1 | grep -vE "^\[ RUN|^Running main|^\[-|^$" | tail -12
    echo "racecheck exit: ${PIPESTATUS[0]}"
  else
    echo "compute-sanitizer: not found"
  fi
fi

if ((ctest_all)); then
  phase "ctest -L gpu"
  timeout "$(limit 90)" ctest --test-dir "$build" -L gpu 2>&1 | tail -15
fi

# OpenMPI: root is refused and ranks beyond the slots too unless allowed.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMP_NUM_THREADS=1
declare -A row
# run NAME SECONDS RANKS ARGS...: one pbf_bench_mpi run; its table row kept.
run() {
  local name=$1 seconds=$2 ranks=$3
  shift 3
  phase "$name: $ranks rank(s) $*"
  local line
  line=$(timeout "$(limit "$seconds")" mpiexec -n "$ranks" "$bench_mpi" --backend cuda "$@" \
    --json "$out/$name.json" 2> >(tee "$out/$name.err" >&2) | tee "$out/$name.out" | tail -1)
  [[ $line == "| "* ]] && row[$name]=$line || row[$name]="| $name: FAILED or cut |"
  echo "${row[$name]}"
}
reference() {
  local name=$1 seconds=$2 count=$3
  phase "$name: single-GPU CudaStepper, $count particles"
  timeout "$(limit "$seconds")" "$bench" --backend cuda --particles "$count" --warmup 3 \
    --steps "$steps" --json "$out/$name.json" --label "$name" 2>&1 | tail -4 | tee "$out/$name.out"
}

run strong-1 60 1 --particles "$particles" --warmup 3 --steps "$steps"
((quick)) || reference cudastepper-strong 40 "$particles"
run weak-1 50 1 --per-rank "$per_gpu" --warmup 3 --steps "$steps"
((quick)) || reference cudastepper-weak 30 "$per_gpu"
for n in 2 4; do
  if ((gpus >= n)); then
    run "strong-$n" 60 "$n" --particles "$particles" --warmup 3 --steps "$steps"
    if ((n == 4)); then
      if ((quick)) && ((${#ab[@]})); then
        for again in "" "-again"; do
          [[ -n $again ]] && run "strong-4-again" 40 4 --particles "$particles" --warmup 3 --steps "$steps"
          for k in "${!ab[@]}"; do
            echo "${ab[$k]}" >"$out/strong-4-ab$k$again.label"
            # A subshell: the environment stays with this row (its table row is read from the JSON).
            (export ${ab[$k]}; run "strong-4-ab$k$again" 40 4 --particles "$particles" --warmup 3 --steps "$steps")
          done
        done
      else
        run "strong-4-again" 40 4 --particles "$particles" --warmup 3 --steps "$steps"
      fi
    fi
    # 2 GPUs at 16M each is the strong run's 32M: the same scene, measured once more.
    ((quick && n == 2)) || run "weak-$n" 80 "$n" --per-rank "$per_gpu" --warmup 3 --steps "$steps"
  else
    echo "skipping $n GPUs: this machine has $gpus"
  fi
done

phase "summary"
python3 - "$out" "$particles" "$per_gpu" <<'EOF' || printf '%s\n' "${row[@]}"
import json, os, sys
out, particles, per_gpu = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def load(name):
    try:
        with open(os.path.join(out, name + ".json")) as f:
            text = f.read().strip()
        # pbf_bench writes {"runs": [...]}; pbf_bench_mpi one object.
        data = json.loads(text)
        return data["runs"][0] if "runs" in data else data
    except Exception:
        return None
def ms(d):
    if d is None: return None
    return d.get("median_ms")
ref_strong, ref_weak = load("cudastepper-strong"), load("cudastepper-weak")
print(f"Strong scaling, {particles:,} particles (ms/step median, slowest rank, barrier to barrier):")
print("| GPUs | ms/step (p10-p90) | speed-up vs 1 GPU | vs CudaStepper | ghost ms | migration ms | particles per GPU | ghosts (max) |")
print("|---:|---:|---:|---:|---:|---:|---|---:|")
base = ms(load("strong-1"))
for n, name in ((1, "strong-1"), (2, "strong-2"), (4, "strong-4"), ("4, again", "strong-4-again"),
                *[(f"4, A/B {open(os.path.join(out, f)).read().strip()}{' (again)' if 'again' in f else ''}", f[:-6])
                  for f in sorted(os.listdir(out)) if f.endswith(".label")]):
    d = load(name)
    if d is None: continue
    m = d["median_ms"]
    per = d["particles_per_rank"]
    print(f"| {n} | {m:.2f} ({d['p10_ms']:.2f}-{d['p90_ms']:.2f}) | {base / m:.2f} | "
          f"{(ms(ref_strong) / m) if ms(ref_strong) else float('nan'):.2f} | {d['ghost_ms']:.2f} | "
          f"{d['migration_ms']:.2f} | {min(per):,}-{max(per):,} | {d.get('ghosts_max', 0):,.0f} |")
print(f"CudaStepper (single GPU, CUDA graphs) at {particles:,}: {ms(ref_strong)} ms/step")
print()
print(f"Weak scaling, {per_gpu:,} particles per GPU:")
print("| GPUs | particles | ms/step (p10-p90) | efficiency vs 1 GPU | ghost ms | migration ms | particles per GPU |")
print("|---:|---:|---:|---:|---:|---:|---|")
base = ms(load("weak-1"))
for n in (1, 2, 4):
    d = load(f"weak-{n}")
    if d is None: continue
    m = d["median_ms"]
    per = d["particles_per_rank"]
    print(f"| {n} | {d['particles']:,} | {m:.2f} ({d['p10_ms']:.2f}-{d['p90_ms']:.2f}) | "
          f"{base / m:.2f} | {d['ghost_ms']:.2f} | {d['migration_ms']:.2f} | {min(per):,}-{max(per):,} |")
print(f"CudaStepper (single GPU, CUDA graphs) at {per_gpu:,}: {ms(ref_weak)} ms/step")
print()
print("Per rank, medians in ms: own step; waiting for its device's border fields; in the refreshes' exchanges; host time from the step's start to the passes")
for name in ("strong-2", "strong-4", "strong-4-again", "weak-2", "weak-4",
             *[f[:-6] for f in sorted(os.listdir(out)) if f.endswith(".label")]):
    d = load(name)
    if d is None or "own_ms_per_rank" not in d: continue
    print(f"{name}: own {d['own_ms_per_rank']}; device wait {d['device_wait_ms_per_rank']}; exchange wait {d['refresh_wait_ms_per_rank']}; before passes {d.get('before_passes_ms_per_rank')}")
EOF
echo "total: $((SECONDS - t0)) s"
