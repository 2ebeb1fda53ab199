# Sourced by the .ci scripts: run named steps, keep each step's output in a
# log, and on failure show that output and name the step, so a failure is
# never silent (a step that fails prints its own error, not just "exit 1").
#
#   step NAME CMD [ARG...]   run CMD; its output goes to a log under $LS_CI_LOGS
#                            (default build-logs/) and is echoed when it fails
#   step_live NAME CMD ...   the same, with the output shown as it runs
#   step_bg NAME CMD ...     start CMD in the background at the lowest CPU
#                            priority (nice 19), its output to the step's log
#   step_wait NAME           wait for a step_bg step; fails as step does
#
# step_bg is for CPU-bound work (builds) that can overlap steps that mostly
# wait on the simulated arm in real time: at nice 19 it takes only the CPU
# those steps leave idle. Background steps still running when the script
# exits (a foreground step failed) are killed.
#
# Both print "== NAME" first and "ci: NAME failed (exit N), log: PATH" on failure,
# then exit with CMD's status (the scripts run with set -e).

LS_CI_LOGS=${LS_CI_LOGS:-$PWD/build-logs}
mkdir -p "$LS_CI_LOGS"
LS_CI_SCRIPT=${LS_CI_SCRIPT:-$(basename "$0")}

_ci_log_path() {
  local slug
  slug=$(printf '%s' "$1" | tr -c 'A-Za-z0-9._-' '-' | cut -c1-60)
  printf '%s/%s.%s.log' "$LS_CI_LOGS" "$LS_CI_SCRIPT" "$slug"
}

# _ci_run quiet|live NAME CMD...: the body of step and step_live.
_ci_run() {
  local mode=$1 name=$2
  shift 2
  local log rc=0
  log=$(_ci_log_path "$name")
  echo "== $name"
  if [ "$mode" = live ]; then
    "$@" 2>&1 | tee "$log" || rc=${PIPESTATUS[0]}
  else
    "$@" >"$log" 2>&1 || rc=$?
  fi
  [ "$rc" -eq 0 ] && return 0
  if [ "$mode" = quiet ]; then
    echo "---- output of '$name' (last 120 lines of $log) ----" >&2
    tail -n 120 "$log" >&2
    echo "---- end of output ----" >&2
  fi
  echo "$LS_CI_SCRIPT: step '$name' failed (exit $rc); full log: $log" >&2
  exit "$rc"
}

step() { _ci_run quiet "$@"; }
step_live() { _ci_run live "$@"; }

declare -A _ci_bg_pid=()

_ci_kill_bg() {
  local pid
  for pid in "${_ci_bg_pid[@]}"; do
    kill -- "-$pid" 2>/dev/null || kill "$pid" 2>/dev/null || true
  done
}
trap _ci_kill_bg EXIT

# ci_background: lower the calling session's CPU weight as a whole. With the
# kernel's autogroup scheduling (sched_autogroup_enabled, on by default in
# Debian's kernels), every session (setsid) is one scheduling group and groups
# share the CPU equally whatever their tasks' nice: a `setsid nice -n 19`
# build measured 73 % of a core against the foreground's 109 % on 2 cores.
# Setting the session's autogroup nice restores what nice 19 promises
# (0.4 % against 173 %). Without autogroup the file is absent and nice alone
# does it.
ci_background() {
  if [ -w /proc/self/autogroup ]; then
    echo 19 >/proc/self/autogroup 2>/dev/null || true
  fi
}
export -f ci_background

step_bg() {
  local name=$1 log
  shift
  log=$(_ci_log_path "$name")
  echo "== $name (started in the background, log: $log)"
  # setsid: its own process group, so the EXIT trap ends the whole tree.
  setsid bash -c 'ci_background; exec nice -n 19 "$@"' _ "$@" >"$log" 2>&1 &
  _ci_bg_pid[$name]=$!
}

step_wait() {
  local name=$1 log rc=0
  log=$(_ci_log_path "$name")
  [ -n "${_ci_bg_pid[$name]:-}" ] || { echo "$LS_CI_SCRIPT: no background step '$name'" >&2; exit 2; }
  wait "${_ci_bg_pid[$name]}" || rc=$?
  unset "_ci_bg_pid[$name]"
  if [ "$rc" -eq 0 ]; then
    echo "== $name: done"
    return 0
  fi
  echo "---- output of '$name' (last 120 lines of $log) ----" >&2
  tail -n 120 "$log" >&2
  echo "---- end of output ----" >&2
  echo "$LS_CI_SCRIPT: step '$name' failed (exit $rc); full log: $log" >&2
  exit "$rc"
}
