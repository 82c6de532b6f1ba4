# Sourced by .ci/run and cmake/check-reliability.sh: `step NAME COMMAND...` runs COMMAND and, once it
# ends, prints how long it took and the time since the first step, so CI's log shows where its time goes.
steps_started=${steps_started:-$(date +%s)}
export steps_started
step() {
  name=$1
  shift
  begun=$(date +%s)
  "$@"
  echo "vkray CI: $name took $(( $(date +%s) - begun )) s ($(( $(date +%s) - steps_started )) s in all)"
}
