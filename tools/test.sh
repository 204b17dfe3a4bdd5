#!/usr/bin/env bash
# Everything CI checks, in order: install, lint, format, types, generated code, the book, the tests.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/_common.sh"

step "install symrb with the test extra"
"$PYTHON" -m pip install --quiet --disable-pip-version-check -e ".[test]"

if [ ! -x /usr/bin/chromium ]; then
    step "install Debian chromium (for the browser test)"
    SUDO=""
    if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends chromium
fi

step "ruff check"
ruff check .
step "ruff format --check"
ruff format --check .
step "mypy"
mypy
step "symrb derive --check"
symrb derive --check

step "book (with the CI subset of the mutation check)"
SYMRB_MUTATION=ci bash tools/book.sh

step "pytest (whole suite, browser test included)"
"$PYTHON" -m pytest

printf '\nall checks passed in %ss\n' "$(( $(date +%s) - start ))"
