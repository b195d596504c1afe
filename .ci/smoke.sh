#!/usr/bin/env bash
# Smoke test of the wheel as a user gets it: build the wheel, install it into a fresh virtual
# environment outside the repository (the dependencies from requirements.lock), and run the main
# commands from another folder. Nothing may be written into the installation.
# Usage: bash .ci/smoke.sh   (after `make setup`; PYTHON picks the interpreter of the new venv)
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/solas-mi-smoke.XXXXXX")
trap 'rm -rf "$work"' EXIT
step() { echo "smoke: $*"; }

step "building the wheel"
"$repo/.venv/bin/python" -m build --wheel --no-isolation --outdir "$work/dist" "$repo" > "$work/build.log" 2>&1 \
  || { cat "$work/build.log"; exit 1; }
wheel=$(ls "$work"/dist/solas_mi-*.whl)
step "installing $(basename "$wheel") into a fresh venv in $work/venv"
"${PYTHON:-python3}" -m venv "$work/venv"
pip=("$work/venv/bin/python" -m pip -q --disable-pip-version-check)
"${pip[@]}" install -r "$repo/requirements.lock"
"${pip[@]}" install --no-deps "$wheel"
"${pip[@]}" check
site=$("$work/venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
# another distribution's top-level scenes/ package must not hide solas-mi's own
mkdir -p "$site/scenes" && : > "$site/scenes/__init__.py"
touch "$work/installed.stamp"

mkdir "$work/run" && cd "$work/run"
S="$work/venv/bin/solas-mi"
PYI="$work/venv/bin/python"
"$PYI" - "$site" <<'PY'
import sys
from solas_mi.resources import resource_dir
scenes = resource_dir("scenes")
assert str(scenes).startswith(sys.argv[1]), f"resources outside the installation: {scenes}"
assert (scenes / "lenses" / "solas_doublet.toml").is_file(), scenes
PY
"$S" --version | grep -qx "solas-mi $("$PYI" -c 'from importlib.metadata import version; print(version("solas-mi"))')"
step "lens list / lens info"
"$S" lens list > list.txt && grep -q "solas-doublet" list.txt  # no pipe: grep -q closing it early is SIGPIPE
"$S" lens info solas-doublet --json > info.json
step "psf, psf-grid"
"$S" psf solas-doublet --field-deg 0,2 --wavelengths-nm 531 --pitch-um 0.5 -o psf.exr
"$S" psf-grid solas-doublet --grid 4x4 --wavelengths-nm 656,531,486 --psf-method geometric --size 64 --pitch-um 2 \
  -o grid.exr 2> grid.log
# progress in a log: a few plain lines, no carriage returns, counting the grid's 4x4x3 PSFs
grep "^psf-grid:" grid.log | tail -n 1 | grep -q "^psf-grid: 48/48 PSFs (100 %" && [ "$(grep -c '^psf-grid:' grid.log)" -le 4 ] \
  && ! grep -q $'\r' grid.log || { echo "smoke: psf-grid progress in a log:"; cat -A grid.log; exit 1; }
step "degrade, render-image"
photo=$("$PYI" -c 'from solas_mi.resources import resource_dir; print(resource_dir("scenes") / "images" / "rocket.png")')
"$S" degrade "$photo" --psf-grid grid.exr -o degraded.exr
"$S" render-image solas-doublet "$photo" --sensor 64x48 --spp 4 -o rendered.exr 2> render.log
[ "$(grep -c '^render: ' render.log)" -le 4 ] && grep -q "^render: 4/4 spp (100 %" render.log && ! grep -q $'\r' render.log \
  || { echo "smoke: render progress in a log:"; cat -A render.log; exit 1; }
step "a scene through lens_camera"
cat > tiny.xml <<'XML'
<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="4"/>
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="48"/><integer name="height" value="32"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
    <shape type="sphere">
        <point name="center" value="0, 0, 20"/><float name="radius" value="0.3"/>
        <emitter type="area"><rgb name="radiance" value="5"/></emitter>
    </shape>
</scene>
XML
"$S" render tiny.xml --lens solas-doublet --spp 4 -o tiny_lens.exr
step "the street experiment, small"
"$S" experiment street --lens solas-doublet -o street --size 160x120 --spp 4 --spp-ideal 4 2> street.log \
  || { cat street.log; exit 1; }
"$S" experiment street-scene -o street_scene > /dev/null
for f in psf.exr grid.exr degraded.exr degraded.png rendered.exr tiny_lens.exr street/street.md street_scene/street.xml; do
  [ -s "$f" ] || { echo "smoke: missing output $f"; exit 1; }
done
written=$(find "$work/venv" -newer "$work/installed.stamp" -type f ! -name '*.pyc' | head -5)
[ -z "$written" ] || { echo "smoke: files written into the installation:"; echo "$written"; exit 1; }
step "all passed (outside the repository: $work/run)"
