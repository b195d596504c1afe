"""Every reader of a file a user or a file names, given what is no regular file under a name it takes:
refused in time (`solas_mi.userfiles`). Before, a FIFO made each wait for ever and /dev/zero was read
until memory ran out (--sensor-model /dev/zero: 2 GB in 14 s)."""

import os

import pytest
from in_time import finished, refused


@pytest.fixture
def odd(tmp_path):
    """A FIFO and a symbolic link to /dev/zero."""
    os.mkfifo(tmp_path / "fifo")
    os.symlink("/dev/zero", tmp_path / "zero")
    return tmp_path


def _named(path, suffix):
    """A name ending in `suffix` for `path` (a FIFO or /dev/zero): a symbolic link beside it."""
    link = path.with_name(path.name + "_link" + suffix)
    os.symlink(path, link)
    return link


def _sensor_naming(path):
    """The sensor of a file whose `qe_curve` names `path` (beside it)."""
    from solas_mi.sensor.files import load_sensor

    sensor = path.with_name("sensor.toml")
    sensor.write_text(f'[sensor]\nqe_curve = "{path.name}"\n')
    return load_sensor(sensor)


def _batch_input(path):
    """A batch's inputs, `path` given by name (hashed before it is read)."""
    from solas_mi.batch.jobs import expand_inputs

    return expand_inputs([path])


def _readers():
    from solas_mi.imageio import read_exr, read_image
    from solas_mi.isp.pipeline import load_isp
    from solas_mi.optics.lens import Lens
    from solas_mi.render.response import table
    from solas_mi.sensor.files import load_sensor
    from solas_mi.sensor.qe import read_csv

    return [
        (load_sensor, ".toml"),
        (load_isp, ".toml"),
        (read_csv, ".csv"),
        (_sensor_naming, ".csv"),
        (table, ".csv"),
        (Lens.load, ".toml"),
        (Lens.load, ".zmx"),
        (Lens.load, ".seq"),
        (Lens.load, ".dat"),
        (read_image, ".png"),
        (read_image, ".exr"),
        (read_exr, ".exr"),
        (_batch_input, ".png"),
    ]


@pytest.mark.parametrize("target", ["fifo", "zero"])
@pytest.mark.parametrize("index", range(len(_readers())))
def test_every_reader_refuses_what_is_no_regular_file(odd, target, index):
    """Each reader of a file a user or a file names (sensor model, ISP file, QE curve, camera response table,
    lens files, images, a batch's inputs), given a FIFO or /dev/zero under a name it takes: refused in time, as no regular
    file (before: a FIFO waited for ever, /dev/zero was read until memory ran out)."""
    reader, suffix = _readers()[index]
    assert "is not a regular file" in refused(reader, _named(odd / target, suffix))


def test_readers_that_only_look_do_not_wait(odd):
    """An image's header read for its size (before reading it) and a former batch's manifest: a FIFO
    gives no size and no manifest, in time."""
    from solas_mi.batch.jobs import Manifest
    from solas_mi.imageio import image_size

    assert finished(image_size, _named(odd / "fifo", ".png")) == {"value": (0, 0, 0)}
    assert finished(Manifest.previous, odd / "fifo") == {"value": {}}


@pytest.mark.parametrize(
    "name, text",
    [
        ("sensor.toml", '[sensor]\ncfa = "{x}"\n'),
        ("isp.toml", '[isp]\ntone = "{x}"\n'),
        ("lens.toml", '[[surface]]\nradius = "{x}"\nthickness = 1\ndiameter = 1\nstop = true\n'),
        ("lens.seq", "{x}\n"),
        ("lens.dat", "{x}\n"),
        ("lens.zmx", "SURF 0\n  DISZ INFINITY\nSURF 1\n  STOP\n  GLAS {x}\n  DIAM 1 1\nSURF 2\n"),
    ],
)
def test_a_huge_line_is_cut_in_the_error(tmp_path, name, text):
    """A line of nearly a megabyte (within the files' bounds) quoted back in a refusal: cut to at most
    MAX_WORD characters a word and MAX_MESSAGE in all (before: the whole line, a one-megabyte message)."""
    from solas_mi.errors import MAX_MESSAGE, MAX_WORD
    from solas_mi.isp.pipeline import load_isp
    from solas_mi.optics.lens import Lens
    from solas_mi.sensor.files import load_sensor

    path = tmp_path / name
    path.write_text(text.format(x="X" * 1_000_000))
    load = {"sensor.toml": load_sensor, "isp.toml": load_isp}.get(name, Lens.load)
    message = refused(load, path)
    assert len(message) <= MAX_MESSAGE + 1 and str(path) in message, message[:300]
    assert "X" * (MAX_WORD - 1) + "…" in message and "X" * (MAX_WORD + 1) not in message  # cut, the quote kept


def test_a_message_of_many_words_is_cut():
    from solas_mi.errors import MAX_MESSAGE, SolasError

    message = str(SolasError("allowed: " + ", ".join(f"name{i}" for i in range(10_000))))
    assert len(message) == MAX_MESSAGE + 1 and message.endswith("…") and message.startswith("allowed: name0, name1")
