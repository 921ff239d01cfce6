# Sourced by the figure scripts: sets $bin to the peritherm binary, $PERITHERM when given
# (e.g. target/release/peritherm from `cargo test --release`), else a fresh release build.
if [ -n "${PERITHERM:-}" ]; then
  bin=$PERITHERM
else
  cargo build --release --quiet
  bin=./target/release/peritherm
fi
