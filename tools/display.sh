# Sourced by the tools that open windows: when $DISPLAY is unset, starts Xvfb on the
# first free display (-noreset: a window opening while the server resets after its
# last client leaves is refused), kills it on exit, and exports DISPLAY.
if [ -z "${DISPLAY:-}" ]; then
  for n in $(seq 90 199); do [ -e "/tmp/.X$n-lock" ] || break; done
  Xvfb ":$n" -screen 0 1280x1024x24 -nolisten tcp -noreset > /dev/null 2>&1 &
  xvfb_pid=$!
  trap 'kill $xvfb_pid' EXIT
  for _ in $(seq 100); do [ -e "/tmp/.X11-unix/X$n" ] && break; sleep 0.05; done
  export DISPLAY=":$n"
fi
