#!/usr/bin/env bash
# The pipeline timing: how much the VTK layer adds to the solver on the GPU machine,
# which has no ParaView and no VTK. Two halves:
#
#   Utilities/gpu/pipeline-run.sh prepare [BUILD]   # here: build pbf_pipeline (the CUDA backend is
#                                                   # compiled in by nvcc) and carry it, with
#                                                   # libPBFFilters and the libraries ldd finds
#                                                   # (VTK's Common* and vtksys, loguru, pugixml,
#                                                   # kissfft; not glibc), into .pipeline/ (ignored)
#   Utilities/gpu/pipeline-run.sh run               # there (device tool, carry [".pipeline"]):
#                                                   # runs it with LD_LIBRARY_PATH=.pipeline/lib
#   Utilities/gpu/pipeline-run.sh fault             # there: only the device-fault checks:
#                                                   # pbf_cuda_fault_tests, one test per process,
#                                                   # and pbf_device_fault auto and cuda
#
# The run times 1M particles at 4 substeps per frame (the target: delivery <= 10% of the frame's
# simulation), page-locked then pageable output memory, without checkpoints, in double
# precision, and 4M particles; logs go to $OUT (else output/pipeline). Documentation/Performance.md
# records the figures.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
carry=$root/.pipeline

# There: log to $OUT/LOG, check the carry holds PROGRAM, load its libraries, say what runs.
on_gpu_machine() {
  out=${OUT:-$root/output/pipeline}
  mkdir -p "$out"
  exec > >(tee "$out/$1") 2>&1
  [[ -x $carry/bin/$2 ]] || { echo "pipeline-gpu-run: no $carry (run prepare here first)"; exit 1; }
  export LD_LIBRARY_PATH=$carry/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
  echo "commit $(cat "$carry/COMMIT") $( [[ -s $carry/DIRTY ]] && echo '(with local changes)')"
  nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv || true
}

case "${1:-}" in
prepare)
  build=${2:-$root/build}
  if [[ ! -f $build/CMakeCache.txt ]]; then
    cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DBUILD_SHARED_LIBS=ON
  fi
  compgen -G "$build/CMakeFiles/*/CMakeCUDACompiler.cmake" > /dev/null ||
    { echo "pipeline-gpu-run: $build has no CUDA compiler: the driver would have no CUDA backend" >&2; exit 1; }
  cmake --build "$build" --target pbf_pipeline pbf_device_fault pbf_cuda_fault_tests -j "$(nproc)"
  rm -rf "$carry"
  mkdir -p "$carry/bin" "$carry/lib"
  programs=("$build/bin/pbf_pipeline" "$build/bin/pbf_device_fault"
    "$(find "$build" -name pbf_cuda_fault_tests -type f -perm -u+x | head -1)")
  cp "${programs[@]}" "$carry/bin/"
  # Everything the drivers load but the C library itself, which the GPU machine has (newer).
  ldd "${programs[@]}" | awk '$3 ~ /^\// { print $3 }' | sort -u | while read -r library; do
    case "$(basename "$library")" in
      libc.so*|libm.so*|libdl.so*|libpthread.so*|librt.so*|ld-linux*) ;;
      *) cp -L "$library" "$carry/lib/" ;;
    esac
  done
  git -C "$root" rev-parse HEAD > "$carry/COMMIT"
  git -C "$root" status --porcelain -- Filters Solver Testing/Pipeline > "$carry/DIRTY" || true
  # Run it here once (no GPU: the CPU backend) so that a broken carry shows before the device.
  LD_LIBRARY_PATH=$carry/lib OMP_WAIT_POLICY=PASSIVE "$carry/bin/pbf_pipeline" --backend openmp \
    --particles 3000 --frames 3 --warmup 1 --work /tmp > /dev/null
  du -sh "$carry"
  ;;
fault)
  on_gpu_machine fault.log pbf_device_fault
  summary=()
  # One gtest per process: a trapped kernel loses the CUDA context for the rest of the process.
  for test in $("$carry/bin/pbf_cuda_fault_tests" --gtest_list_tests | awk '/^[^ ]/ { suite = $1 } /^  / { print suite $1 }'); do
    echo; echo "== pbf_cuda_fault_tests $test"
    if timeout 120 "$carry/bin/pbf_cuda_fault_tests" --gtest_filter="$test" > "$out/$test.log" 2>&1; then
      grep -q "SKIPPED \]" "$out/$test.log" && status=SKIPPED || status=passed
    else
      status="FAILED (exit $?)"
    fi
    tail -n 25 "$out/$test.log"
    summary+=("$test: $status")
  done
  for mode in auto cuda; do
    echo; echo "== pbf_device_fault $mode"
    if timeout 120 "$carry/bin/pbf_device_fault" "$mode"; then
      summary+=("pbf_device_fault $mode: passed")
    else
      summary+=("pbf_device_fault $mode: FAILED (exit $?)")
    fi
  done
  echo; echo "== summary"
  printf '  %s\n' "${summary[@]}"
  ! printf '%s\n' "${summary[@]}" | grep -q FAILED
  ;;
run)
  on_gpu_machine pipeline.log pbf_pipeline
  echo "cores: $(nproc); $(uname -sr)"
  ldd "$carry/bin/pbf_pipeline" | grep -E "not found" && exit 1
  work=$(mktemp -d)
  driver() {
    echo; echo "== pbf_pipeline $*"
    timeout 120 "$carry/bin/pbf_pipeline" --work "$work" "$@" || echo "!! exit $?"
  }
  driver --particles 1e6 --frames 40 --warmup 5 --compare-pageable 15
  driver --particles 1e6 --frames 25 --warmup 5 --checkpoint-interval 0
  driver --particles 1e6 --frames 15 --warmup 3 --precision double
  driver --particles 4e6 --frames 15 --warmup 3
  ;;
*)
  sed -n '2,17p' "$0"
  exit 2
  ;;
esac
