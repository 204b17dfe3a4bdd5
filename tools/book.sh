#!/usr/bin/env bash
# Build the executed book from a fresh clone:
#   install, regenerate the generated code, check it is committed as generated, verify every claim,
#   then build the book with every page executed and every warning treated as an error.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/_common.sh"

step "install symrb with the book extra"
"$PYTHON" -m pip install --quiet --disable-pip-version-check -e ".[book]"

step "symrb derive (regenerate symrb/_generated)"
symrb derive
step "symrb derive --check"
symrb derive --check

# Keep book/_build/verify.json only from this run; drop the old HTML and doctrees so every page
# is read and executed again.
rm -rf book/_build/html book/_build/.doctrees book/_build/jupyter_execute book/_build/verify.json
mkdir -p book/_build

step "symrb verify (every claim; writes book/_build/verify.json for the claims and errata pages)"
symrb verify --output book/_build/verify.json

step "jupyter-book build -W --keep-going book"
jupyter-book build -W --keep-going book

printf '\nbook built in %ss: book/_build/html/index.html\n' "$(( $(date +%s) - start ))"
