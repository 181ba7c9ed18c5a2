"""Files from elsewhere, checked before anything reads them: URDFs, MJCFs, logs, settings.

A file a user names may be truncated, malformed, hostile (an XML entity bomb, mesh paths
that point at ``/etc/passwd``), endless (``/dev/zero``, a FIFO) or huge (a 2 GB sparse file).
Each check here ends such a file in a ComGraspError (the caller's class: InvalidInputError
for descriptions, LogError for logs, ResumeError for a run's files) within bounded time and
memory, before any library sees it:

- only regular files are opened (a FIFO would block, a device never end), at most a size
  limit, read at most that many bytes (a file that grows meanwhile is cut, then refused);
- XML is parsed by expat with no DOCTYPE allowed: no entity can be declared, so none can
  expand (billion laughs) or fetch (external entities); URDF and MJCF need no DTD;
- every file a description names (URDF ``mesh filename``, MJCF ``file`` attributes) must
  resolve, symbolic links followed, inside the description's folder or a package folder the
  caller gave (``package://PKG/...`` under one of them); other URI schemes are refused.

Nothing here writes a file.
"""

from __future__ import annotations

import json
import os
import stat
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from xml.parsers import expat

from comgrasp_pin.errors import ComGraspError, InvalidInputError

MIB = 1 << 20
MAX_DESCRIPTION_BYTES = 16 * MIB
"""A URDF or MJCF (s): the project's UR5 is 11 kB, descriptions with every link and
material inline stay below 2 MB; 16 MiB leaves room and bounds the parser's tree (~10x)."""
MAX_CSV_BYTES = 1024 * MIB
"""A CSV log: an hour at 500 Hz of a 7-joint arm with velocities (22 columns of ~12
characters) is ~0.5 GB; the limit refuses a 2 GB file before reading it."""
MAX_CSV_HEADER_BYTES = 1 * MIB
"""A CSV's first line: 3 columns of ~30 characters per joint is 90 kB for 1000 joints."""
MAX_SETTINGS_BYTES = 16 * MIB
"""A run's settings JSON or a bag's metadata.yaml: a few kB; 16 MiB is surely not one."""
FILE_ATTRIBUTES = (
    ("mesh", "filename"), ("mesh", "file"), ("texture", "file"), ("hfield", "file"),
    ("skin", "file"), ("include", "file"), ("model", "file"),
)  # fmt: skip
"""(element, attribute) naming a file: URDF ``<mesh filename>``; MJCF assets and includes."""
ROS1_MAGIC = b"#ROSBAG V2.0\n"  # the first line of a ROS 1 bag file
MJCF_DIRS = ("meshdir", "texturedir", "assetdir")  # <compiler> folders MJCF files resolve in


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):  # fmt: skip
        if test(mode):
            return name
    return "not a regular file"


def regular_file(path: str | Path, what: str, max_bytes: int,
                 error: type[ComGraspError] = InvalidInputError) -> Path:  # fmt: skip
    """``path`` when it is a regular file (links followed) of at most ``max_bytes``.

    Raises:
        error: missing, not a regular file (folder, FIFO, device), or too large.
    """
    path = Path(path)
    try:
        info = path.stat()
    except FileNotFoundError:
        raise error(f"{what} not found: {path}") from None
    except (OSError, ValueError) as exc:  # permission, a name with a NUL byte, a loop
        raise error(f"cannot open {what} {path}: {exc}") from None
    if not stat.S_ISREG(info.st_mode):
        raise error(f"{what} {path} is {_kind(info.st_mode)}, not a regular file")
    if info.st_size > max_bytes:
        raise error(f"{what} {path} is {info.st_size} bytes; at most {max_bytes} are read "
                    f"({max_bytes // MIB} MiB)")  # fmt: skip
    return path


def _read_start(path, what: str, max_bytes: int, error: type[ComGraspError], limit: int,
                line: bool) -> tuple[Path, bytes]:  # fmt: skip
    """(the checked path, its first ``limit`` + 1 bytes, or its first line up to that)."""
    path = regular_file(path, what, max_bytes, error)
    try:
        with path.open("rb") as f:
            return path, f.readline(limit + 1) if line else f.read(limit + 1)
    except OSError as exc:
        raise error(f"cannot read {what} {path}: {exc.strerror or exc}") from None


def read_bytes(path: str | Path, what: str, max_bytes: int,
               error: type[ComGraspError] = InvalidInputError) -> bytes:  # fmt: skip
    """The bytes of a regular file of at most ``max_bytes`` (see ``regular_file``)."""
    path, data = _read_start(path, what, max_bytes, error, max_bytes, line=False)
    if len(data) > max_bytes:
        raise error(f"{what} {path} grew past {max_bytes} bytes while it was read")
    return data


def read_text(path: str | Path, what: str, max_bytes: int,
              error: type[ComGraspError] = InvalidInputError) -> str:  # fmt: skip
    """The UTF-8 text of a regular file of at most ``max_bytes``."""
    data = read_bytes(path, what, max_bytes, error)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{what} {path} is not UTF-8 text (byte {exc.start}): {exc.reason}") from None


class _Doctype(Exception):
    pass


def _refuse_doctype(*_args) -> None:
    raise _Doctype


def parse_xml(text: str, source: str, kind: str,
              error: type[ComGraspError] = InvalidInputError) -> ET.Element:  # fmt: skip
    """The root of the XML document ``text``, refused if it has a DOCTYPE (so entities).

    ``source`` names the file, ``kind`` what it should be ("URDF", "MJCF").

    Raises:
        error: a DOCTYPE or entity declaration, or XML that is not well formed (where).
    """
    scan = expat.ParserCreate()
    scan.StartDoctypeDeclHandler = _refuse_doctype
    scan.EntityDeclHandler = _refuse_doctype
    try:
        scan.Parse(text, True)
    except _Doctype:
        raise error(f"cannot read {source} as a {kind}: it declares a DOCTYPE or entities, "
                    "which a URDF or MJCF never needs and which can expand without bound (an "
                    "entity bomb); remove them") from None  # fmt: skip
    except expat.ExpatError as exc:
        raise error(f"cannot read {source} as a {kind}: not well-formed XML (truncated or "
                    f"damaged?): {exc}") from None  # fmt: skip
    return ET.fromstring(text)


def _inside(path: Path, roots: Sequence[Path]) -> bool:
    real = Path(os.path.realpath(path))
    return any(real == root or root in real.parents for root in roots)


def _referenced(root: ET.Element, folder: Path) -> list[tuple[str, list[Path]]]:
    """(name as written, the paths it may resolve to) of every file the description names.

    No paths for ``package://`` URIs. An MJCF name may resolve in any of its <compiler>
    folders (meshdir, texturedir, assetdir; each may be absolute): every one is returned,
    so that a check of them all does not depend on which MuJoCo uses for which element.
    """
    bases = {folder}
    for compiler in root.iter("compiler"):
        bases |= {folder / str(compiler.get(k)) for k in MJCF_DIRS if compiler.get(k)}
    out = []
    for element, attribute in FILE_ATTRIBUTES:
        for node in root.iter(element):
            name = node.get(attribute)
            if name is None:
                continue
            path = name.removeprefix("file://")
            out.append((name, [] if name.startswith("package://") else [b / path for b in bases]))
    return out


def check_referenced_files(root: ET.Element, description: Path, what: str,
                           package_dirs: Sequence[str | Path] = (),
                           error: type[ComGraspError] = InvalidInputError) -> None:  # fmt: skip
    """Every file the description names resolves inside its folder or a package folder.

    Raises:
        error: a name that points elsewhere (``..``, an absolute path, a link out, a
            ``package://`` path that climbs out of its package) or another URI scheme.
    """
    folder = Path(os.path.realpath(description)).parent
    packages = [Path(os.path.realpath(d)) for d in package_dirs]
    roots = [folder, *packages]
    allowed = f"inside {folder}" + "".join(f" or {p}" for p in packages)
    for name, paths in _referenced(root, folder):
        if name.startswith("package://"):  # package://PKG/rest: PKG/rest under each package
            rest = name.removeprefix("package://")
            bad = not rest or any(not _inside(p / rest, [p]) for p in packages or [folder])
            bad = bad or Path(rest).is_absolute() or ".." in Path(rest).parts
        else:
            bad = "://" in name.removeprefix("file://") or not all(
                _inside(path, roots) for path in paths
            )
        if bad:
            raise error(f"{what} names the file {name!r}, which is not {allowed}: a "
                        "description may use only files in its own folder or the package "
                        "folders given (--package-dir)")  # fmt: skip


def read_description(path: str | Path, what: str = "URDF",
                     package_dirs: Sequence[str | Path] = ()) -> str:  # fmt: skip
    """The checked text of a URDF or MJCF file.

    Checked: a regular file of at most MAX_DESCRIPTION_BYTES, UTF-8, XML without a DOCTYPE,
    every file it names inside its folder or a package folder.

    Raises:
        InvalidInputError: what is wrong with the file, and what is valid.
    """
    text = read_text(path, f"{what} file", MAX_DESCRIPTION_BYTES)
    root = parse_xml(text, str(path), what)
    check_referenced_files(root, Path(path), f"{what} file {path}", package_dirs)
    return text


def read_json(path: str | Path, what: str, error: type[ComGraspError] = InvalidInputError):
    """The value of a JSON file of at most MAX_SETTINGS_BYTES.

    Raises:
        error: not a regular file, too large, not UTF-8, nested too deep for the parser, or
            not JSON (where).
    """
    text = read_text(path, what, MAX_SETTINGS_BYTES, error)
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise error(f"{what} {path} is not JSON (truncated or damaged?): {exc}") from None
    except RecursionError:  # [[[[... nested past the parser's stack: no settings file is
        raise error(f"{what} {path} nests too deep to be a settings file") from None


def first_line(path: str | Path, what: str, max_bytes: int, max_line_bytes: int,
               error: type[ComGraspError] = InvalidInputError) -> str:  # fmt: skip
    """The first line (UTF-8) of a regular file of at most ``max_bytes``.

    The line itself at most ``max_line_bytes``: a CSV's header, a file without newlines not
    read whole.

    Raises:
        error: see ``regular_file``; a first line too long, or not UTF-8.
    """
    path, line = _read_start(path, what, max_bytes, error, max_line_bytes, line=True)
    if len(line) > max_line_bytes:
        raise error(f"{what} {path}: its first line is longer than {max_line_bytes} bytes, "
                    "not a header")  # fmt: skip
    try:
        return line.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(f"{what} {path} is not UTF-8 text (byte {exc.start}): {exc.reason}") from None


def ros_bag(path: str | Path, error: type[ComGraspError] = InvalidInputError) -> Path:
    """What rosbags opens: a ROS 1 ``.bag`` file, or a ROS 2 bag's folder (or its file's).

    A ROS 1 bag: a regular file that starts as one (its chunks, compressed or not, are read
    one at a time). A ROS 2 bag: ``metadata.yaml`` a regular file of at most
    MAX_SETTINGS_BYTES, YAML; the storage files it lists (``rosbags`` looks for them in the
    folder by name) regular files (a FIFO would block the reader); the bag not compressed
    (decompressing writes a whole file, of any size, to a temporary folder: decompress it
    first, ``ros2 bag decompress``).

    Raises:
        error: what is wrong, and what is valid.
    """
    path = Path(path)
    try:
        info = path.stat()
    except FileNotFoundError:
        raise error(f"bag not found: {path}") from None
    except (OSError, ValueError) as exc:
        raise error(f"cannot open the bag {path}: {exc}") from None
    if stat.S_ISREG(info.st_mode) and path.suffix == ".bag":
        if _read_start(path, "ROS 1 bag", 1 << 62, error, 12, line=True)[1] != ROS1_MAGIC:
            raise error(f"{path} is not a ROS 1 bag (version 2.0): give a ROS 1 .bag file, or "
                        "a ROS 2 bag's folder, .db3 or .mcap")  # fmt: skip
        return path
    if stat.S_ISREG(info.st_mode) and path.suffix in (".db3", ".mcap"):
        path = path.parent
    elif not stat.S_ISDIR(info.st_mode):
        raise error(f"bag {path} is {_kind(info.st_mode)}: give a ROS 2 bag's folder, its "
                    ".db3 or .mcap file, or a ROS 1 .bag file")  # fmt: skip
    from ruamel.yaml import YAML
    from ruamel.yaml.error import YAMLError

    text = read_text(path / "metadata.yaml", "bag metadata", MAX_SETTINGS_BYTES, error)
    try:
        meta = YAML(typ="safe").load(text)
        info = meta["rosbag2_bagfile_information"]
        files = [str(name) for name in info.get("relative_file_paths", [])]
        compression = str(info.get("compression_format", "") or "")
    except (YAMLError, KeyError, TypeError, AttributeError) as exc:
        raise error(f"{path / 'metadata.yaml'} is not a ROS 2 bag's metadata: "
                    f"{type(exc).__name__}: {exc}") from None  # fmt: skip
    if compression:
        raise error(f"bag {path} is compressed ({compression}); decompressing it would write a "
                    "file of any size: decompress it first (ros2 bag decompress)")  # fmt: skip
    for name in files:
        regular_file(path / Path(name).name, f"bag {path}: storage file", 1 << 62, error)
    return path
