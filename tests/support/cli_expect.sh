# Shared by the CLI tests (tests/cli/*.sh; source it after setting T, the scratch folder).
# expect2 PATTERN CMD...: CMD must exit 2 (bad input) with PATTERN in its output.
expect2() {
  local pat=$1; shift
  set +e; "$@" > "$T/out.txt" 2>&1; local rc=$?; set -e
  [ $rc -eq 2 ] || { echo "expected exit 2, got $rc: $*"; cat "$T/out.txt"; exit 1; }
  grep -q -- "$pat" "$T/out.txt" || { echo "message lacks '$pat':"; cat "$T/out.txt"; exit 1; }
}
