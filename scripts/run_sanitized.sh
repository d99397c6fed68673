#!/usr/bin/env bash
# The test suite again under AddressSanitizer and UndefinedBehaviorSanitizer (build-asan/, see
# scripts/build_sanitized.sh), then each libFuzzer harness for 30 s on its corpus (build-fuzz/,
# two at a time on 2 cores). CI runs it after scripts/run_tests.sh. Any sanitizer report fails
# the test that made it; a crash found by a harness fails the run (build/fuzz/<name>/crash-*).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/scripts/install_deps.sh"
"$here/scripts/build_sanitized.sh"
cd "$here/build-asan"
# Leaks are not checked: the third-party libraries the reports use (VTK, Mesa, fontconfig) keep
# allocations to the end by design.
export ASAN_OPTIONS="detect_leaks=0:abort_on_error=1:strict_string_checks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# Left out here (they run in the normal suite): the doc-test and the two statistical campaigns, which repeat code
# the rest of the suite covers on twenty seeds each and would take a quarter of an hour under
# the sanitizers.
campaigns="IndependentDiagnosis.TwentyCleanSeedsInBothSetupStylesAddNothing"
campaigns+="|Diagnosis.OverTwentyNoiseSeedsCleanDataAddsAtMostOnce"
# and the doc-test, whose commands the suite's own command tests cover
campaigns+="|Docs.CommandsRun"
ctest --output-on-failure -j"$(nproc)" --timeout 1800 -E "^($campaigns)\$"
# A fixed libFuzzer seed: the same clone fuzzes the same inputs first (a CI run is repeatable);
# longer runs (tests/fuzz/run.sh 3600) use random seeds.
TOLVER_FUZZ_SEED="${TOLVER_FUZZ_SEED:-1}" "$here/tests/fuzz/run.sh" "${TOLVER_FUZZ_SECONDS:-30}"
