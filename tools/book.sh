#!/usr/bin/env bash
# Build the executed book from a fresh clone:
#   set up the Python (the active virtual environment, else .venv, created on first use), install,
#   check that the generated code is what the derivations emit (never rewriting tracked files),
#   verify every claim, optionally run the CI subset of the mutation check (SYMRB_MUTATION=ci),
#   then build the book with every page executed and warnings as errors.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/_common.sh"

step "Python environment and symrb with the book extra"
use_python
install_symrb book

step "symrb derive --check (symrb/_generated is what the derivations emit)"
symrb derive --check

# Keep book/_build/{verify,mutation}.json only from this run; drop the old HTML and doctrees so
# every page is read and executed again.
rm -rf book/_build/html book/_build/.doctrees book/_build/jupyter_execute \
    book/_build/verify.json book/_build/mutation.json
mkdir -p book/_build

step "symrb verify (every claim; writes book/_build/verify.json for the claims and errata pages)"
symrb verify --output book/_build/verify.json

if [ "${SYMRB_MUTATION:-}" = "ci" ]; then
    step "mutation check, CI subset (writes book/_build/mutation.json for the claims page)"
    "$PYTHON" tools/mutate.py --subset ci --json book/_build/mutation.json
fi

step "jupyter-book build -W --keep-going book"
book_start=$(date +%s)
"$PYTHON" tools/build_book.py -W --keep-going book

printf '\nbook built in %s s: book/_build/html/index.html\n' "$(($(date +%s) - book_start))"
