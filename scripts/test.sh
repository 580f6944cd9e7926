#!/usr/bin/env bash
# The test command: installs what is missing, builds, runs every test through ctest.
# Exit code = result.
#   scripts/test.sh             Release build in build/ (the CI command).
#   scripts/test.sh --sanitize  AddressSanitizer + UndefinedBehaviorSanitizer: the whole suite,
#                               built with gcc in build-sanitize/, then the libFuzzer targets of
#                               tests/fuzz/, built with clang in build-fuzz/ (CI runs both).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

sanitize() {
  FLATSOS_SANITIZE=1 "$root/scripts/install_deps.sh"
  # Exported before the build too: gtest_discover_tests runs the test programs while building.
  # A sanitizer report exits 66 (not 1, which the command-line tests expect for bad input).
  # Leaks inside Debian's libraries are suppressed in cmake/lsan.supp, each with its reason.
  local asan=detect_leaks=1:check_initialization_order=1:strict_init_order=1
  export ASAN_OPTIONS=$asan:detect_stack_use_after_return=1:exitcode=66
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:exitcode=66
  export LSAN_OPTIONS=suppressions=$root/cmake/lsan.supp
  local status=0
  FLATSOS_BUILD_DIR="$root/build-sanitize" FLATSOS_BUILD_TYPE=RelWithDebInfo \
    "$root/scripts/build.sh" -DFLATSOS_SANITIZE=ON
  # The longest runs are in the Release suite only: under the sanitizers each took 50-280 s and
  # their code is exercised by the shorter tests (CI's time limit is 90 min).
  local long_runs=(
    OpenSimModels.TheRecedingHorizonLoopReachesItsTargetAlsoOnAWeakerOrStrongerPlant
    FreePath.TheOptimizedPathsPlanIsValidCheaperAndNoSmallMoveLowersItsCost
    CollocationReference.WithTheJointPathFreeItConvergesObeysTheLawsAndBeatsThePrescribedPath
    FreePath.SpansThatGrowPutTheKnotsWhereTheTransferIsFastAndLowerItsCost
    ShortestTransfer.ARicherBasisIsNeverSlowerAndNearTheLeastDurationAlongThePath
    CollocationReference.TheMeshConvergesToATenthOfAPercent
    FreePath.ATorqueModelTooCoarseForTheOptimizedPathIsRefinedUntilItsPlanIsSolved
    FreePath.TheJointNewtonMethodReachesTheQuasiNewtonMethodsOptimum
    CollocationReference.RichFlatnessPlansComeWithinOnePercentAndNeverBelow
    FreePath.AStartPlanInACoarserNestedBasisLeadsToTheSamePlan
    CollocationReference.TheFlatnessFreePathComesWithinTwoPercentWithAnExecutablePlan
    CollocationReference.AGradedMeshConvergesWhereTheTransferStartsFast  # 8 s in Release: three collocations
    RelaxedReference.AlongTheReferencesPathTheFlatnessPlanCostsTheSameOnceTheReferenceStopsSwitching  # 9 s
    StaticOptimization.Arm26AgreesWithOpenSimsStaticOptimization
    Arm26OpenSim2.TheTutorialsForwardSimulationIsReproducedWithOpenSim2MusclesAndGeometricPaths  # 276 s
    # 11 s in Release (a 200-interval collocation, two 3 s replays at 1e-10 and 1e-12); the
    # nonlinear effort's code runs in the elbow's OpenLoopEffort tests.
    OpenLoopEffort.SquaredExcitationsOnThePapersArmMatchTheCollocationOptimum
    # 13 and 7 s in Release (arm26 imported, planned twice); the fallback is a second plan, whose
    # code the other plans run.
    OpenLoopEffort.Arm26sSquaredExcitationsArePlannedOnUniformSpansWhereTheGradedOnesFindNone
    OpenLoopEffort.Arm26WithDeGrooteFreglyMusclesIsPlannedOnUniformSpansWhereTheGradedOnesFindNone
    # 70-110 s each at -O1, most of it importing arm26 again; their code runs in the others.
    IpoptLinearSolvers.CollocationAgrees
    OpenSimModels.TheSosOptimumIsWithinOnePercentAboveAnIndependentDenseGridBound
    TaskRegion.ARegionOutsideTheRangesIsRefused
    TaskRegion.IsThePosturesSpanWidenedByTheMarginAndClippedToTheRanges
    Tracking.RefusesAControllerWithoutAReference
    # Each imports arm26 and solves its inverse problem again (6-13 s in Release); the inverse
    # problem's code runs under the sanitizers in InverseProblem.Arm26AlongTheTutorialsMotion...
    InverseProblem.Arm26FramesKeepTheBoundsAndTheMotionsTorques
    InverseProblem.Arm26ExcitationsReplayedBySimbodyFollowTheMotion
    InverseProblem.UnpennatedArm26IsWithinOnePercentOfTheCollocationOptimumAlongTheSameMotion
    DeGrooteImport.Arm26sThelenMusclesBecomeDeGrooteFreglysAsMocoMapsThem  # two imports
    package_install_and_consume  # packaging, not memory: the Release suite checks it
  )
  # The command-line tests skip their longest runs too (the left leg's controller).
  export FLATSOS_SANITIZER_RUN=1
  local skip
  skip="^($(IFS='|'; echo "${long_runs[*]}"))\$"
  (cd "$root/build-sanitize" && ctest --output-on-failure --timeout 1200 -j "$(nproc)" -E "$skip") || status=1

  # The fuzzers: clang, ASan + UBSan + libFuzzer (tests/fuzz/run_fuzzer.sh).
  cmake -S "$root" -B "$root/build-fuzz" -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFLATSOS_FUZZ=ON -DFLATSOS_BUILD_TESTS=OFF \
    -DFLATSOS_BUILD_EXAMPLES=OFF >/dev/null
  cmake --build "$root/build-fuzz" --target flatsos_fuzzers --parallel "$(nproc)"
  (cd "$root/build-fuzz" && ctest --output-on-failure) || status=1
  return $status
}

if (($#)); then
  if [[ $# == 1 && $1 == --sanitize ]]; then sanitize; exit; fi
  echo "usage: scripts/test.sh [--sanitize]" >&2
  exit 2
fi
"$root/scripts/install_deps.sh"
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure --timeout 1200 -j "$(nproc)"
