#!/usr/bin/env bash
# Where the decomposed CUDA stepper's GPUs wait, in one call of the device tool on a
# machine with several GPUs (carry [".deps"]): builds pbf_bench_mpi without ParaView and the CUPTI
# tracer (Utilities/gpu/cupti_trace.cpp: the GPU machine has no Nsight Systems), runs pbf_bench_mpi
# with the tracer injected at P particles on N ranks and on 1 rank, and prints,
# per rank and per step, the GPU's busy and idle time and the idle gaps grouped by the work around
# them (Utilities/gpu/timeline.py). The analysis goes under $OUT (else
# output/gpu-timeline).
#   Utilities/gpu/timeline.sh [--particles P] [--ranks N] [--steps S] [--no-single]
#   Utilities/gpu/timeline.sh --bench "ARGS" [--steps S]
# --bench traces one pbf_bench run on one GPU instead (e.g. "--refined 0.005 --until 0.3 --modes
# defaults": where the step of the scene users run spends its time) and analyses its last S steps.
# Extra environment (A/B switches of DeviceSubdomainStepper.h) passes through to the ranks.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
out=${OUT:-$root/output/gpu-timeline}
build=${PBF_GPU_BUILD:-/tmp/pbf-gpu-timeline-build}
particles=32000000
ranks=4
steps=6
single=1
bench_args=""
while (($#)); do
  case $1 in
    --bench) bench_args=$2; shift 2 ;;
    --particles) particles=$2; shift 2 ;;
    --ranks) ranks=$2; shift 2 ;;
    --steps) steps=$2; shift 2 ;;
    --no-single) single=0; shift ;;
    *) sed -n '2,10p' "$0"; exit 2 ;;
  esac
done
mkdir -p "$out"
exec > >(tee "$out/timeline.log") 2>&1
t0=$SECONDS
phase() { echo; echo "== [$((SECONDS - t0)) s] $*"; }

phase "machine"
nvidia-smi --query-gpu=index,name,driver_version --format=csv,noheader 2>&1 | head -8
cuda=$(dirname "$(dirname "$(command -v nvcc)")")
cupti_inc=$(dirname "$(ls "$cuda"/include/cupti.h "$cuda"/extras/CUPTI/include/cupti.h 2>/dev/null | head -1)")
cupti_lib=$(dirname "$(ls "$cuda"/lib64/libcupti.so "$cuda"/lib/libcupti.so "$cuda"/extras/CUPTI/lib64/libcupti.so 2>/dev/null | head -1)")
echo "CUPTI: $cupti_inc $cupti_lib"
command -v ompi_info >/dev/null && ompi_info --parsable --all 2>/dev/null |
  grep -E "mpi_built_with_cuda_support:value" | head -2

phase "build"
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
if cmake -S "$root" -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DPBF_SOLVER_ONLY=ON \
    -DBUILD_TESTING=OFF -DCMAKE_CUDA_ARCHITECTURES=90 -DPBF_JSON_INCLUDE_DIR="$root/.deps/json" \
    >"$out/configure.log" 2>&1 &&
  cmake --build "$build" -j "$(nproc)" \
    --target "$([[ -n $bench_args ]] && echo pbf_bench || echo pbf_bench_mpi)" \
    >"$out/build.log" 2>&1; then
  echo "build: ok"
else
  tail -n 40 "$out/configure.log" "$out/build.log"
  exit 1
fi
bench_mpi=$build/Solver/Tools/pbf_bench_mpi
tracer=$build/libpbf_cupti_trace.so
g++ -std=c++17 -O2 -shared -fPIC -I"$cupti_inc" "$root/Utilities/gpu/cupti_trace.cpp" -o "$tracer" \
  -L"$cupti_lib" -Wl,-rpath,"$cupti_lib" -lcupti || { echo "the CUPTI tracer did not build"; exit 1; }

export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMP_NUM_THREADS=1
profile() {
  local name=$1 n=$2
  phase "$name: $n rank(s), $particles particles, 3 + $steps steps, GPU activity traced"
  mkdir -p "$out/$name"
  PBF_TRACE_DIR="$out/$name" CUDA_INJECTION64_PATH="$tracer" timeout 150 mpiexec -n "$n" \
    "$bench_mpi" --backend cuda --particles "$particles" --warmup 3 --steps "$steps" 2>&1 | tail -4
  python3 "$root/Utilities/gpu/timeline.py" --steps $((steps - 1)) "$out/$name"/trace-*.csv
  gzip -f "$out/$name"/trace-*.csv
}
if [[ -n $bench_args ]]; then
  phase "pbf_bench --backend cuda $bench_args, GPU activity traced"
  mkdir -p "$out/bench"
  read -r -a args <<<"$bench_args"
  PBF_TRACE_DIR="$out/bench" CUDA_INJECTION64_PATH="$tracer" timeout 300 \
    "$build/Solver/Tools/pbf_bench" --backend cuda "${args[@]}" 2>&1 | tail -4
  python3 "$root/Utilities/gpu/timeline.py" --steps "$steps" "$out/bench"/trace-*.csv
  gzip -f "$out/bench"/trace-*.csv
  echo "total: $((SECONDS - t0)) s"
  exit 0
fi
profile "ranks-$ranks" "$ranks"
((single)) && profile "ranks-1" 1
echo "total: $((SECONDS - t0)) s"
