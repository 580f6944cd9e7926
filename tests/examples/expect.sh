# Sourced by the command-line tests: a scratch folder and `expect`, which runs a command and
# checks its exit code and a text in its output; failures set fail=1.
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
fail=0
expect() {  # expect <exit code> <text in output> -- command...
  local code=$1 text=$2; shift 3
  local out rc
  out=$("$@" 2>&1); rc=$?
  if [[ $rc != "$code" ]] || ! grep -qF -- "$text" <<<"$out"; then
    echo "FAILED: $* -> exit $rc (want $code), output lacks '$text':"; echo "$out" | head -5; fail=1
  else echo "ok: $*"; fi
}
