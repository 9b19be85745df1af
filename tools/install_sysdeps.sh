#!/usr/bin/env bash
# System packages the project needs beyond Python wheels: the bare-metal ARM
# cross compiler and its C library headers, used by `make test` to prove the
# FC core compiles for a Cortex-M4F. Installs from Debian when missing and we
# are root with apt; otherwise says what to do and lets the test skip itself.
set -u
if command -v arm-none-eabi-gcc >/dev/null 2>&1 && [ -f /usr/lib/arm-none-eabi/include/math.h ]; then
    exit 0
fi
if [ "$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then
    echo "installing gcc-arm-none-eabi and libnewlib-arm-none-eabi (Cortex-M4F portability check)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null && \
    apt-get install -y -qq --no-install-recommends gcc-arm-none-eabi libnewlib-arm-none-eabi >/dev/null || \
        echo "warning: apt-get could not install the ARM cross compiler; the portability test will skip" >&2
else
    echo "note: arm-none-eabi-gcc missing and apt-get unavailable (or not root);" \
         "install gcc-arm-none-eabi + libnewlib-arm-none-eabi to run the Cortex-M4F portability check" >&2
fi
exit 0
