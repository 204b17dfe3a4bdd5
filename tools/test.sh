#!/usr/bin/env bash
# Everything CI checks, in order: the Python environment (the active virtual environment, else
# .venv), lint, format, types, the book (generated code checked, claims verified, every page
# executed; built once here), then the whole test suite with the doctests of symrb.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/_common.sh"

step "Python environment and symrb with the test extra"
use_python
install_symrb test

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

step "book (tools/book.sh, with the CI subset of the mutation check)"
SYMRB_MUTATION=ci bash tools/book.sh

step "pytest (whole suite, browser test included, and the doctests of symrb)"
"$PYTHON" -m pytest -n auto --dist loadfile --durations=10

printf '\nall checks passed in %s s\n' "$(elapsed)"
