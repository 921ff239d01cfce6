#!/usr/bin/env bash
# Rewrites the tables of README.md and docs/*.md from the committed figure files of
# validation/ (the blocks between `<!-- figures:NAME -->` and `<!-- /figures:NAME -->`), through
# the test that otherwise fails when they differ. Usage: bash scripts/update-docs.sh
set -euo pipefail
cd "$(dirname "$0")/.."
PERITHERM_BLESS=1 cargo test --release --quiet --test cli figures::docs_show_the_committed_figures
