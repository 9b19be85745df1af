#!/usr/bin/env bash
# System packages the project needs beyond Python wheels, each for one test:
# - the bare-metal ARM cross compiler and its C library headers, used by `make test` to
#   prove the FC core compiles for a Cortex-M4F;
# - Debian's `chromium`, in which tests/docs/test_browser.py opens the HTML benchmark
#   report and the docs site (headless).
# Installs from Debian what is missing when we are root with apt; otherwise says what to
# do and lets the test skip itself. Never fatal: each install fails alone, with a warning.
set -u

have_arm() {
    command -v arm-none-eabi-gcc >/dev/null 2>&1 && [ -f /usr/lib/arm-none-eabi/include/math.h ]
}
have_chromium() {
    command -v chromium >/dev/null 2>&1
}

if have_arm && have_chromium; then
    exit 0
fi
if [ "$(id -u)" != "0" ] || ! command -v apt-get >/dev/null 2>&1; then
    have_arm || echo "note: arm-none-eabi-gcc missing and apt-get unavailable (or not root);" \
        "install gcc-arm-none-eabi + libnewlib-arm-none-eabi to run the Cortex-M4F portability check" >&2
    have_chromium || echo "note: chromium missing and apt-get unavailable (or not root);" \
        "install Debian's chromium to check the report and docs pages in a browser" >&2
    exit 0
fi

export DEBIAN_FRONTEND=noninteractive
apt-get update -qq >/dev/null || echo "warning: apt-get update failed; trying the installs anyway" >&2
if ! have_arm; then
    echo "installing gcc-arm-none-eabi and libnewlib-arm-none-eabi (Cortex-M4F portability check)"
    apt-get install -y -qq --no-install-recommends gcc-arm-none-eabi libnewlib-arm-none-eabi >/dev/null || \
        echo "warning: apt-get could not install the ARM cross compiler; the portability test will skip" >&2
fi
if ! have_chromium; then
    echo "installing chromium (the report and docs pages checked in a headless browser)"
    apt-get install -y -qq --no-install-recommends chromium >/dev/null || \
        echo "warning: apt-get could not install chromium; the browser tests will skip" >&2
fi
exit 0
