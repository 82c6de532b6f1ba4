#!/bin/sh
# The Slurm example of docs/many-views.md (docs/slurm-views.sh) on a real one-node Slurm
# cluster, as CI runs it after the suite: Debian 12's slurm-wlm and munge, with a MUNGE key, munged,
# slurmctld and slurmd started in a temporary folder (proctrack/linuxproc, task/none, no
# accounting). The script's array of 4 tasks renders views of the built-in scene; while its tasks
# run, task 1 is requeued (`scontrol requeue`) and task 2 cancelled part way (`scancel`). A merge
# then must refuse the parts, naming task 2's views missing; task 2 is submitted again alone
# (`sbatch --array=2`), as the script's header says; the merge of the parts must hold every view
# once, with the records of an unsharded run of the same views, and each view's EXR must hold that
# run's pixels.
#
#   sh cmake/check-slurm.sh [VKRAY]     (as root; VKRAY defaults to build/vkray)
#
# Every wait has a timeout; the tasks are cancelled, the daemons stopped and the folder removed
# whatever happens. A failure prints the last lines of the daemons' and tasks' logs, then one line
# saying what failed, and exits non-zero.
set -eu
cd "$(dirname "$0")/.."
source_dir="$(pwd)"
began=$(date +%s)
vkray="${1:-build/vkray}"
case "$vkray" in /*) ;; *) vkray="$source_dir/$vkray" ;; esac
say() { echo "vkray slurm check: $*"; }
at() { echo "$(( $(date +%s) - began )) s"; }

# What the array renders: views of the built-in scene, a quarter of them a task; enough for the tasks
# to be running still when one is requeued and another cancelled (a task renders for 3-5 s here).
views=400
width=320
height=240
share=$(( views / 4 ))

if [ "$(id -u)" -ne 0 ]; then say "FAILED: run it as root (it starts munged, slurmctld and slurmd)"; exit 1; fi
if [ ! -x "$vkray" ]; then say "FAILED: no vkray at $vkray (build the project first)"; exit 1; fi
# What the check takes for granted of the script: 4 tasks of 2 CPUs each.
if ! grep -qx '#SBATCH --array=0-3' docs/slurm-views.sh || ! grep -qx '#SBATCH --cpus-per-task=2' docs/slurm-views.sh; then
  say "FAILED: docs/slurm-views.sh no longer asks for --array=0-3 and --cpus-per-task=2: update this check"; exit 1
fi
if [ "$(nproc)" -lt 2 ]; then say "FAILED: the script's tasks ask for 2 CPUs, and this machine has $(nproc)"; exit 1; fi
sh cmake/install-deps.sh cmake/debian-packages-slurm.txt
installed=$(date +%s)

work="$(mktemp -d)"
chmod 755 "$work"  # munged runs as munge and reaches its folder through this one
export SLURM_CONF="$work/slurm.conf"
out="$work/views"
whole="$work/whole"
stage="starting"
munged_pid=""
slurmctld_pid=""
slurmd_pid=""
mounted=""  # file systems mounted for the check (below)
failure=""

stop() {  # PID...: SIGTERM, then SIGKILL after 10 s; only the processes this script started
  for pid in "$@"; do if [ -n "$pid" ]; then kill "$pid" 2>/dev/null || true; fi; done
  for pid in "$@"; do
    [ -n "$pid" ] || continue
    tries=0
    while kill -0 "$pid" 2>/dev/null && [ $tries -lt 100 ]; do sleep 0.1; tries=$((tries + 1)); done
    kill -9 "$pid" 2>/dev/null || true
    wait "$pid" 2>/dev/null || true
  done
}

finish() {
  status=$?
  set +e
  if [ $status -ne 0 ]; then
    for log in "$work"/slurm/slurmctld.log "$work"/slurm/slurmd.log "$work"/slurm/*.out "$work"/munge/munged.out \
               "$work"/vkray-views-*.log "$work"/*.err; do
      [ -s "$log" ] || continue
      case "$log" in *.out) [ -s "${log%.out}.log" ] && continue ;; esac  # a daemon's log, if it opened one
      echo "--- the last lines of $(basename "$log"):"
      tail -n 12 "$log"
    done
  fi
  # The tasks first, while the daemons that run them are up; then the daemons.
  if [ -n "$slurmctld_pid" ] && kill -0 "$slurmctld_pid" 2>/dev/null; then
    jobs="$(timeout 10 squeue -h -o %A 2>/dev/null)"
    [ -z "$jobs" ] || timeout 10 scancel $jobs >/dev/null 2>&1
    tries=0
    while [ -n "$(timeout 10 squeue -h -o %A 2>/dev/null)" ] && [ $tries -lt 100 ]; do sleep 0.1; tries=$((tries + 1)); done
  fi
  stop "$slurmd_pid" "$slurmctld_pid" "$munged_pid"
  for place in $mounted; do umount "$place" 2>/dev/null || true; done
  rm -rf "$work"
  if [ $status -eq 0 ]; then
    say "passed in $(at) ($(( $(date +%s) - installed )) s after the package install), the cluster stopped and removed"
  else
    say "FAILED while $stage: ${failure:-exit $status}"
  fi
  exit $status
}
trap finish EXIT
trap 'failure="stopped by SIGINT"; exit 130' INT
trap 'failure="stopped by SIGTERM"; exit 143' TERM

fail() { failure="$*"; exit 1; }  # the line is printed last, after the logs

# waitfor SECONDS WHAT COMMAND...: runs COMMAND every 0.1 s until it succeeds; fails after SECONDS.
waitfor() {
  limit=$1
  what=$2
  shift 2
  deadline=$(( $(date +%s) + limit ))
  until "$@"; do
    [ "$(date +%s)" -lt "$deadline" ] || fail "$what did not come within $limit s"
    sleep 0.1
  done
}
# alive NAME PID OUTPUT: fails at once, with the daemon's last words, once it has exited.
alive() { kill -0 "$2" 2>/dev/null || fail "$1 exited: $(tail -n 1 "$3")"; }
# Slurm's commands, cut off after 20 s rather than retrying for minutes where slurmctld went away.
slurm() { timeout 20 "$@"; }

stage="starting munged"
mkdir -m 755 "$work/munge"  # munged wants its socket's folder open to all; the key stays 0400
chown munge:munge "$work/munge"
as_munge="setpriv --reuid=munge --regid=munge --init-groups"
$as_munge mungekey --create --keyfile="$work/munge/munge.key"
chmod 0400 "$work/munge/munge.key"
socket="$work/munge/munge.socket"
$as_munge munged --foreground --socket="$socket" --key-file="$work/munge/munge.key" \
  --pid-file="$work/munge/munged.pid" --seed-file="$work/munge/munged.seed" >"$work/munge/munged.out" 2>&1 &
munged_pid=$!
munged_up() { alive munged "$munged_pid" "$work/munge/munged.out" && test -S "$socket"; }
waitfor 10 "munged's socket" munged_up
munge -n -S "$socket" | unmunge -S "$socket" >/dev/null || fail "a MUNGE credential did not decode"

stage="starting slurmctld and slurmd"
# The node and the controller are this machine, reached on the loopback address: a machine whose
# name resolves nowhere (a chroot without it in /etc/hosts) runs the cluster too.
host="$(hostname -s)"
cpus="$(nproc)"
memory=$(( $(awk '/^MemTotal:/ { print $2 }' /proc/meminfo) / 1024 / 4 ))  # MB, a quarter of the machine's
mkdir -p "$work/slurm/state" "$work/slurm/spool"
# Ports of its own, so that a Slurm already on the machine is left alone. OverSubscribe lets the 4
# tasks (2 CPUs each) run at once on fewer CPUs. A requeued task waits cred_expire seconds (120 by
# default), then for the next pass of a scheduler (every 30 s for the backfill one, 60 s for the
# main one by default) before it starts again.
cat >"$SLURM_CONF" <<EOF
ClusterName=vkray-check
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=16817
SlurmdPort=16818
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket,cred_expire=5
StateSaveLocation=$work/slurm/state
SlurmdSpoolDir=$work/slurm/spool
SlurmctldPidFile=$work/slurm/slurmctld.pid
SlurmdPidFile=$work/slurm/slurmd.pid
SlurmctldLogFile=$work/slurm/slurmctld.log
SlurmdLogFile=$work/slurm/slurmd.log
PlugStackConfig=$work/slurm/plugstack.conf
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
KillWait=5
SchedulerParameters=bf_interval=1,sched_interval=1
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$memory State=UNKNOWN
PartitionName=check Nodes=$host Default=YES MaxTime=10 State=UP OverSubscribe=FORCE:4
EOF
: >"$work/slurm/plugstack.conf"
# Slurm 22.05's slurmd starts its cgroup plugin whatever the proctrack and task plugins (23.02 added
# CgroupPlugin=disabled), on the cgroup version the process is in: a machine without the cgroup file
# systems mounted (a chroot: CI's fresh Debian) gets them for the check's time, as /proc/self/cgroup
# names them (one unified hierarchy, or v1 controllers), unmounted at its end, last first.
mounted=""
if ! grep -q ' /sys/fs/cgroup' /proc/mounts; then
  if ! grep -q ' /sys ' /proc/mounts; then mount -t sysfs sysfs /sys && mounted="/sys"; fi
  if [ "$(grep -cv '^0::' /proc/self/cgroup)" -eq 0 ]; then
    mount -t cgroup2 cgroup2 /sys/fs/cgroup && mounted="/sys/fs/cgroup $mounted"
  else
    mount -t tmpfs cgroups /sys/fs/cgroup && mounted="/sys/fs/cgroup $mounted"
    for hierarchy in $(cut -d: -f2 /proc/self/cgroup | grep -v '^$'); do
      case "$hierarchy" in name=*) options="none,$hierarchy" ;; *) options="$hierarchy" ;; esac
      folder="/sys/fs/cgroup/${hierarchy#name=}"
      mkdir -p "$folder" && mount -t cgroup -o "$options" cgroup "$folder" && mounted="$folder $mounted"
    done
  fi
fi
slurmctld -D -i >"$work/slurm/slurmctld.out" 2>&1 &
slurmctld_pid=$!
slurmd -D >"$work/slurm/slurmd.out" 2>&1 &
slurmd_pid=$!
node_idle() {
  alive slurmctld "$slurmctld_pid" "$work/slurm/slurmctld.out"
  alive slurmd "$slurmd_pid" "$work/slurm/slurmd.out"
  [ "$(timeout 10 sinfo -h -n "$host" -o %T 2>/dev/null)" = idle ]
}
waitfor 30 "the node, idle in sinfo," node_idle
say "a one-node cluster is up ($host, $cpus CPUs) at $(at)"

stage="submitting the array"
cd "$work"  # the tasks' logs (vkray-views-%a.log) go here
task_log() { echo "$work/vkray-views-$1.log"; }
log_end() { [ ! -s "$(task_log "$1")" ] || echo ": its log ends \"$(tail -n 1 "$(task_log "$1")")\""; }
submit() {  # sbatch's options: the script's array (0-3) unless given
  VKRAY="$vkray" MODEL="" OUT="$out" VIEWS=$views WIDTH=$width HEIGHT=$height \
    slurm sbatch --parsable "$@" "$source_dir/docs/slurm-views.sh" | cut -d';' -f1
}
job="$(submit)"
[ -n "$job" ] || fail "sbatch gave no job id"
say "job $job: docs/slurm-views.sh's array of 4 tasks, $views views of ${width}x$height"

stage="requeuing and cancelling running tasks"
records() { if [ -f "$out/manifest-shard-$1-of-4.jsonl" ]; then wc -l <"$out/manifest-shard-$1-of-4.jsonl"; else echo 0; fi; }
some_views() {  # TASK: running, with 2 views or more rendered
  state="$(slurm squeue -h -j "${job}_$1" -o %T 2>/dev/null || true)"
  case "$state" in
    PENDING | CONFIGURING | RUNNING) ;;
    *) fail "task $1 ended (${state:-gone from squeue}) after $(records "$1") views, before it could be acted on$(log_end "$1")" ;;
  esac
  [ "$state" = RUNNING ] && [ "$(records "$1")" -ge 2 ]
}
waitfor 60 "task 2's first views" some_views 2
waitfor 5 "task 1's first views" some_views 1
slurm scancel "${job}_2"
cancelled_after=$(records 2)
slurm scontrol requeue "${job}_1"
requeued_after=$(records 1)
say "task 2 cancelled after $cancelled_after of its $share views, task 1 requeued after $requeued_after, at $(at)"
[ "$cancelled_after" -lt "$share" ] || fail "task 2 had rendered its views when cancelled: give the tasks more views"
[ "$requeued_after" -lt "$share" ] || fail "task 1 had rendered its views when requeued: give the tasks more views"

stage="rendering the views unsharded, for comparison"  # while task 1 waits to start again
timeout 120 "$vkray" render "" --orbit $views --width $width --height $height -o "$whole/view-{index:05}.exr" \
  >/dev/null 2>"$work/whole.err" || fail "the unsharded render failed: $(tail -n 1 "$work/whole.err")"

say "the unsharded run rendered, at $(at)"
stage="waiting for the array's end"
array_done() { [ -z "$(slurm squeue -h -j "$1" -o %A)" ]; }
waitfor 90 "the array's end" array_done "$job"
field() { slurm scontrol show job "$1" | tr ' ' '\n' | sed -n "s/^$2=//p" | head -n 1; }
for task in 0 1 3; do
  [ "$(field "${job}_$task" JobState)" = COMPLETED ] ||
    fail "task $task ended $(field "${job}_$task" JobState), not COMPLETED$(log_end $task)"
done
[ "$(field "${job}_2" JobState)" = CANCELLED ] || fail "task 2 ended $(field "${job}_2" JobState), not CANCELLED"
[ "$(field "${job}_1" Restarts)" = 1 ] || fail "task 1 was not started again once (Restarts=$(field "${job}_1" Restarts))"
# resumed TASK AT_LEAST: the task's render, run again, rendered only the views of its shard it lacked.
resumed() {
  line="$(grep "views written, .* complete already (shard $1 of 4, $views views in all)" "$(task_log "$1")" | tail -n 1)"
  written="${line#vkray: }"
  written="${written%% *}"
  complete="${line#*views written, }"
  complete="${complete%% *}"
  [ -n "$line" ] || fail "task $1's log has no line of the views it wrote$(log_end "$1")"
  [ $((written + complete)) -eq $share ] && [ "$complete" -ge "$2" ] ||
    fail "task $1, run again after $2 of its $share views, says: $line"
  say "task $1 run again: $written views written, $complete complete already, at $(at)"
}
resumed 1 "$requeued_after"

stage="merging the parts without the views task 2 did not render"
parts() { ls "$out"/manifest-shard-*-of-*.jsonl; }
missing="$(/usr/bin/python3 -c '
import json, sys
done = set()
for line in open(sys.argv[1]):
    try:
        done.add(json.loads(line)["index"])
    except ValueError:
        pass  # a line cut off by the kill: that view is missing
print(len([i for i in range(2, int(sys.argv[2]), 4) if i not in done]), min(set(range(2, int(sys.argv[2]), 4)) - done))
' "$out/manifest-shard-2-of-4.jsonl" $views)"
expected="the parts hold $((views - ${missing% *})) of the run's $views views; missing: ${missing#* }"
if timeout 60 "$vkray" manifest merge $(parts) -o "$out/manifest.jsonl" >/dev/null 2>"$work/merge.err"; then
  fail "the merge of parts that lack task 2's views succeeded"
fi
grep -qF -e "$expected," -e "$expected (" "$work/merge.err" ||
  fail "the merge said \"$(cat "$work/merge.err")\", not \"$expected...\""
[ ! -e "$out/manifest.jsonl" ] || fail "the merge that failed wrote $out/manifest.jsonl"

stage="running task 2 again alone"
again="$(submit --array=2)"
[ -n "$again" ] || fail "sbatch gave no job id"
waitfor 60 "the end of task 2 run again (job $again)" array_done "$again"
[ "$(field "${again}_2" JobState)" = COMPLETED ] ||
  fail "task 2 run again ended $(field "${again}_2" JobState)$(log_end 2)"
resumed 2 "$cancelled_after"

stage="merging the parts and comparing them with the unsharded run"
[ "$(parts | wc -l)" -eq 4 ] || fail "$(parts | wc -l) manifest parts, not 4: $(parts | tr '\n' ' ')"
timeout 60 "$vkray" manifest merge $(parts) -o "$out/manifest.jsonl" >/dev/null 2>"$work/merge.err" ||
  fail "the merge failed: $(cat "$work/merge.err")"
timeout 120 /usr/bin/python3 - "$out" "$whole" "$views" >"$work/compare.err" 2>&1 <<'EOF' || fail "$(tail -n 1 "$work/compare.err")"
import json, os, sys
import numpy as np
import OpenImageIO as oiio

out, whole, views = sys.argv[1], sys.argv[2], int(sys.argv[3])

def records(folder):
    """The manifest's records by index, its file names without their folder, once each opens."""
    with open(os.path.join(folder, "manifest.jsonl")) as manifest:
        records = [json.loads(line) for line in manifest.read().splitlines()]
    for record in records:
        if not os.path.isfile(os.path.join(folder, record["exr"])):
            sys.exit(f"{folder}/manifest.jsonl: view {record['index']}'s {record['exr']} does not open from there")
        record["exr"] = os.path.basename(record["exr"])
    return sorted(records, key=lambda record: record["index"])

def pixels(path):
    image = oiio.ImageInput.open(path)
    if not image:
        sys.exit(f"cannot read {path}: {oiio.geterror()}")
    names, data = image.spec().channelnames, image.read_image(oiio.FLOAT)
    image.close()
    return names, data

merged, unsharded = records(out), records(whole)
if [record["index"] for record in merged] != list(range(views)):
    sys.exit(f"the merged manifest does not hold each of views 0-{views - 1} once: {[r['index'] for r in merged]}")
different = [a["index"] for a, b in zip(merged, unsharded) if a != b]
if len(merged) != len(unsharded) or different:
    sys.exit(f"the merged manifest's records are not the unsharded run's: views {different} differ")
names = [f"view-{index:05}.exr" for index in range(views)]
expected = sorted(names + ["manifest.jsonl"] + [f"manifest-shard-{task}-of-4.jsonl" for task in range(4)])
files = sorted(os.listdir(out))
if files != expected:
    sys.exit(f"the views' folder holds {sorted(set(files) - set(expected))[:5]} besides the views and manifests, "
             f"and lacks {sorted(set(expected) - set(files))[:5]}")
for name in names:
    (channels, a), (channels_whole, b) = pixels(os.path.join(out, name)), pixels(os.path.join(whole, name))
    if channels != channels_whole or not np.array_equal(a, b):
        sys.exit(f"{name} is not the unsharded run's (channels {channels} against {channels_whole}, or the pixels)")
print(f"the merged manifest holds each of the {views} views once, with the unsharded run's records; "
      f"each view's EXR has its pixels")
EOF
say "$(cat "$work/compare.err"), at $(at)"
