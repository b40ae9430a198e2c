# Sourced by scripts/sanitize.sh and scripts/fuzz.sh: how the sanitizer build reports. Every report is
# fatal with exit code 86, which no iqc path uses (0 ok, 1 input, 2 usage, 3 internal error), so a test
# that expects exit 1 fails on a sanitizer report instead of passing. Suppressions: scripts/lsan.supp
# (only code of Debian's libraries, never iqc's).
IQC_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export ASAN_OPTIONS="exitcode=86:abort_on_error=0:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:exitcode=86:${UBSAN_OPTIONS:-}"
export LSAN_OPTIONS="exitcode=86:suppressions=$IQC_ROOT/scripts/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
