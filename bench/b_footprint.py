"""Benchmark 7: footprint of the portable firmware cross-built for a
Cortex-M4F (flash, RAM) and proof of no heap."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import tempfile
from collections import defaultdict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from common import BUILD, ROOT, BenchError, Row, Section

CC = "arm-none-eabi-gcc"
CXX = "arm-none-eabi-g++"
TARGET = ["-Os", "-mcpu=cortex-m4", "-mthumb", "-mfpu=fpv4-sp-d16", "-mfloat-abi=hard", "-ffunction-sections",
          "-fdata-sections", "-DNDEBUG", "-Wall", "-Wextra", "-Werror=implicit-function-declaration"]
CFLAGS = ["-std=c11", *TARGET]
# C++ (the kinematics) needs libstdc++-arm-none-eabi-newlib for <cmath>; its definitions and -f options
# (-fno-exceptions, -fno-rtti, EIGEN_NO_MALLOC) come from its target in the manifest.
CXXFLAGS = ["-std=c++17", *TARGET]
# No nosys.specs: the firmware formats and parses with firmware/common/ls_fmt.c, so nothing reaches newlib's
# stdio or system calls; a libc function that needed one would fail the link here.
LDFLAGS = ["--specs=nano.specs", "-nostartfiles", "-Wl,--gc-sections"]
# Link-time optimisation of the image's units (not of fw_sizes.c, whose object is read, never linked). Fat
# objects: the per-part table comes from a second link of the same objects without LTO (LTO merges every
# unit into a few partitions, so its map cannot say which part a byte belongs to).
LTO = ["-flto", "-ffat-lto-objects"]
ALLOCATORS = {"malloc", "free", "calloc", "realloc", "_malloc_r", "_free_r", "_calloc_r", "_realloc_r", "_sbrk",
              "_sbrk_r", "aligned_alloc", "posix_memalign", "memalign", "_Znwj", "_Znaj", "_ZdlPv", "_ZdaPv"}
NANOPB_RUNTIME = ("pb_encode.c", "pb_decode.c", "pb_common.c")
# libsodium's sources firmware/auth calls into (HMAC-SHA256, SHA-256, the constant-time compare and wipe), as
# its own build compiles them; CONFIGURED is the macro by which a build without its autotools says it set the
# platform up (no #warning), NATIVE_LITTLE_ENDIAN that the Cortex-M4 is little-endian.
SODIUM_SOURCES = ("src/libsodium/crypto_auth/hmacsha256/auth_hmacsha256.c",
                  "src/libsodium/crypto_hash/sha256/cp/hash_sha256_cp.c",
                  "src/libsodium/crypto_verify/sodium/verify.c", "src/libsodium/sodium/utils.c")
SODIUM_INCLUDE = "src/libsodium/include"
SODIUM_DEFINES = ["CONFIGURED=1", "NATIVE_LITTLE_ENDIAN=1"]
# What the image does with each library of landscaped's link closure that is not one of our targets.
# A library missing here fails the benchmark: someone must decide what it means on a bare board.
LIBRARIES = {
    "nanopb::protobuf-nanopb-static": "nanopb runtime, compiled from Debian's nanopb source package",
    "PkgConfig::SODIUM": "libsodium's HMAC-SHA256 (firmware/auth), compiled from Debian's libsodium source package",
    "PkgConfig::EIGEN": "header-only",
    "m": "newlib's libm (-lm)",
    "Threads::Threads": "landscaped's threads (process glue): none on the bare board",
}
# The host's system headers: the cross compiler has its own (newlib); nanopb's headers come with its runtime.
HOST_INCLUDE = Path("/usr/include")
MANIFEST = BUILD / "footprint" / "portable.txt"
# The goals for the mcu profile's image (docs/performance.md section 7).
FLASH_GOAL_KIB = 128
RAM_GOAL_KIB = 192
CACHE = Path(os.environ.get("LS_BENCH_CACHE", Path.home() / ".cache" / "landscape-bench"))


@dataclass
class FwTarget:
    """One portable library of the firmware as the host build compiles it (from the manifest)."""

    name: str
    sources: list[Path] = field(default_factory=list)
    includes: list[Path] = field(default_factory=list)
    defines: list[str] = field(default_factory=list)
    options: list[str] = field(default_factory=list)


CXX_SUFFIXES = (".cpp", ".cc", ".cxx")


def obj_stem(src: Path) -> str:
    """Object name for the per-part breakdown: the DBC code (also named landscape.c) stays apart."""
    if "libsodium" in str(src):
        return "sodium_" + src.stem
    return src.stem.replace("landscape", "dbc_landscape" if "dbc" in str(src) else "landscape")


def read_manifest(path: Path) -> tuple[list[FwTarget], list[str], dict[str, list[str]]]:
    """The portable libraries of landscaped, the other libraries it links, as bench/CMakeLists.txt
    computed them from the main build's targets, and each profile's definitions (CMakeLists.txt LS_PROFILE)."""
    if not path.is_file():
        raise BenchError(f"{path} is missing: configure the bench project (bench/run.py, or "
                         "cmake -S bench -B build-bench) to generate it")
    targets: list[FwTarget] = []
    libraries: list[str] = []
    profiles: dict[str, list[str]] = {}
    for number, line in enumerate(path.read_text().splitlines(), 1):
        key, _, value = line.partition(" ")
        items = [x for x in value.split(";") if x]
        if key == "target":
            targets.append(FwTarget(value))
        elif key == "library":
            libraries.append(value)
        elif key == "profile":
            name, _, defs = value.partition(" ")
            profiles[name] = [d for d in defs.split(";") if d.strip()]
        elif key in ("sources", "includes", "defines", "options") and targets:
            t = targets[-1]
            if key == "sources":
                t.sources = [Path(x) for x in items]
            elif key == "includes":
                t.includes = [Path(x) for x in dict.fromkeys(items) if Path(x) != HOST_INCLUDE]
            elif key == "defines":
                t.defines = items
            else:
                t.options = [x for x in items if x.startswith("-f")]  # code generation; warnings are the host's
        else:
            raise BenchError(f"{path}:{number}: unexpected line {line!r}: reconfigure build-bench")
    if not targets:
        raise BenchError(f"{path} lists no firmware library: reconfigure build-bench")
    unknown = [lib for lib in libraries if lib not in LIBRARIES]
    if unknown:
        raise BenchError(f"landscaped links {', '.join(unknown)}, which the Cortex-M4F image does not know: "
                         "add it to LIBRARIES in bench/b_footprint.py (what it is on a bare board), or move it "
                         "to an OS part (LS_FOOTPRINT_OS_DIRS in bench/CMakeLists.txt)")
    if not {"linux", "mcu"} <= profiles.keys():
        raise BenchError(f"{path} names no linux and mcu profiles: reconfigure build-bench")
    return targets, libraries, profiles


def run(cmd: list[str], **kw: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300, **kw)  # type: ignore[call-overload]


def nanopb_runtime() -> Path:
    """Debian's nanopb source package (the runtime matching Debian's generator), fetched once per
    machine (debian_source). The PyPI `nanopb` sdist and wheel carry the generator only, and
    libnanopb-dev only an x86 archive."""
    return debian_source("nanopb", "nanopb", NANOPB_RUNTIME, "its generator made the codecs")


def sodium_sources() -> Path:
    """Debian's libsodium source package, of the version landscaped links (libsodium-dev), fetched once
    per machine (debian_source): libsodium-dev carries an x86 archive only."""
    return debian_source("libsodium", "libsodium-dev", SODIUM_SOURCES, "firmware/auth links it")


def debian_source(package: str, installed: str, needed: tuple[str, ...], why: str) -> Path:
    """The unpacked Debian source package `package` at the version of the installed `installed`, fetched
    with a private apt configuration (the system's own apt sources, as deb-src; nothing of the system's apt
    state changes) and kept in $LS_BENCH_CACHE (default ~/.cache/landscape-bench), so a fresh build-bench (a
    CI clone) does not fetch it again. `needed`: the files it must hold."""
    version = run(["dpkg-query", "-W", "-f=${Version}", installed]).stdout.strip()
    if not version:
        raise BenchError(f"Debian's {installed} is not installed ({why}): run .ci/setup")
    upstream = version.split("-")[0].split(":")[-1]
    src = CACHE / f"{package}-{version.replace(':', '_')}" / f"{package}-{upstream}"
    if all((src / f).is_file() for f in needed):
        return src
    parts = deb_src_parts()
    if not parts:
        raise BenchError("no Debian archive in /etc/apt/sources.list or /etc/apt/sources.list.d/ to derive a deb-src "
                         f"entry from; unpack {package}'s source into {src}/")
    src.parent.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix=f"lsbench-{package}-", dir=src.parent.parent) as tmpdir:
        dest = Path(tmpdir)
        apt = dest / "apt"
        for d in ("parts", "lists/partial", "cache/archives/partial"):
            (apt / d).mkdir(parents=True, exist_ok=True)
        for name, text in parts.items():
            (apt / "parts" / name).write_text(text)
        opts = ["-o", "Dir::Etc::SourceList=/dev/null", "-o", f"Dir::Etc::SourceParts={apt / 'parts'}",
                "-o", f"Dir::State::Lists={apt / 'lists'}", "-o", f"Dir::Cache={apt / 'cache'}"]
        up = run(["apt-get", *opts, "update"])
        got = run(["apt-get", *opts, "source", f"{package}={version}"], cwd=dest) if up.returncode == 0 else up
        fetched = dest / src.name
        if not all((fetched / f).is_file() for f in needed):
            raise BenchError(f"cannot fetch Debian's {package} {version} source package: "
                             f"{(got.stderr or got.stdout).strip()[-200:]}")
        src.parent.mkdir(exist_ok=True)
        if not src.exists():  # another run may have put it there meanwhile
            fetched.rename(src)
    return src


ONE_LINE_DEB = re.compile(r"^(\s*)deb(\s)", re.MULTILINE)
DEB822_TYPES = re.compile(r"^Types:.*$", re.MULTILINE)


def deb_src_parts(etc: Path = Path("/etc/apt")) -> dict[str, str]:
    """The system's apt sources turned into deb-src sources, one apt SourceParts file per system file.

    Both formats apt reads: the one-line `deb URI suite components` of sources.list and *.list (what a
    Debian installer and mmdebstrap write), and the deb822 stanzas of *.sources (what Debian 12's cloud
    images write). Returns {file name: text}; empty when no file names an archive."""
    out: dict[str, str] = {}
    one_line = [etc / "sources.list", *sorted((etc / "sources.list.d").glob("*.list"))]
    for n, path in enumerate(p for p in one_line if p.is_file()):
        entries = [ONE_LINE_DEB.sub(r"\1deb-src\2", line) for line in path.read_text().splitlines()
                   if ONE_LINE_DEB.match(line)]
        if entries:
            out[f"src{n}.list"] = "\n".join(entries) + "\n"
    for n, path in enumerate(sorted((etc / "sources.list.d").glob("*.sources"))):
        text = path.read_text()
        if DEB822_TYPES.search(text):
            out[f"src{n}.sources"] = DEB822_TYPES.sub("Types: deb-src", text)
    return out


def map_breakdown(map_text: str) -> dict[str, dict[str, int]]:
    """Bytes per input file and kind (flash / ram) from the linker map's kept input sections."""
    out: dict[str, dict[str, int]] = defaultdict(lambda: {"flash": 0, "ram": 0})
    discarded = map_text.find("Discarded input sections")
    memmap = map_text.find("Linker script and memory map")
    body = map_text[memmap:] if memmap >= 0 else map_text[discarded:]
    pat = re.compile(r"^ (\.(?:text|rodata|data|bss)[^\s]*)?\s*\n?\s+0x([0-9a-f]+)\s+0x([0-9a-f]+)\s+(\S+)$", re.M)
    for m in pat.finditer(body):
        name, size, path = m.group(1) or "", int(m.group(3), 16), m.group(4)
        if size == 0 or not name:
            continue
        kind = "ram" if name.startswith(".bss") else "flash"
        if name.startswith(".data"):
            out[path]["ram"] += size
        out[path][kind] += size
    return out


def label(path: str) -> str:
    if "libgcc" in path:
        return "libgcc (double-precision soft float: the FPU is single-precision)"
    if "libm.a" in path:
        return "newlib libm (double-precision)"
    if "libc_nano" in path:
        return "newlib-nano libc"
    name = Path(path).name
    for key, lab in (("ls_cmd_table", "generated dispatch table"), ("ls_core", "firmware/core"),
                     ("cmd_", "firmware/core"), ("ls_units", "firmware/core"),
                     ("ls_run", "firmware/core"), ("ls_wire", "firmware/core"), ("ls_utf8", "firmware/core"),
                     ("ls_fmt", "firmware/common/ls_fmt.c"), ("ls_kin", "firmware/kinematics"),
                     ("ls_motion", "firmware/motion/ls_motion.c"),
                     ("ls_react", "firmware/motion/ls_react.c"), ("ls_control", "firmware/control"),
                     ("ls_manual", "firmware/control"),
                     ("ls_net", "firmware/net"),
                     ("ls_isotp", "firmware/isotp"), ("ls_traj", "firmware/motion/ls_traj.c"),
                     ("ls_ramp", "firmware/motion/ls_ramp.c"),
                     ("ls_robot_model", "firmware/model"), ("pb_", "nanopb runtime"),
                     ("ls_auth", "firmware/auth"), ("sodium_", "libsodium (HMAC-SHA256, SHA-256)"),
                     ("landscape.pb", "generated nanopb codecs"),
                     ("dbc_landscape", "generated DBC code (cantools)"), ("hal.", "hal wrappers"),
                     ("fw_main", "bench main + HAL stubs, with the static ls_core_t and ls_net_t")):
        if key in name:
            return lab
    return re.sub(r"^\d+_", "", name)  # an object this table does not know yet, without its build index


# Where the static RAM goes: the parts bench/footprint/fw_sizes.c measures (fp_<name>), what each one is and
# the limits that size it (fp_limit_<LIMIT> carries each limit's value). Indented parts belong to the object
# above them; "rest" is what the listed parts leave of it.
RAM_PARTS = [
    ("core", "`ls_core_t` (g_core)", ""),
    ("core__paths", "path queues `motion.paths`",
     "LS_PATH_MAX x LS_PATH_MAX_POINTS x ls_path_point_t ({path_point} B)"),
    ("core__prog", "the path program `motion.prog`", "LS_MOTION_MAX_SEGS (a path and the segment closing a cycle) x "
     "ls_motion_seg_t ({motion_seg} B)"),
    ("core__sessions", "sessions (each with its last answer)", "LS_MAX_SUPERVISORS x ls_session_t ({session} B: "
     "LS_DOWNLINK_MAX)"),
    ("core__up", "decoded uplink `up`", "ls_Uplink: the schema's max_count/max_size (protocol/landscape.options)"),
    ("core__down_note", "answer and notice being built", "2 x ls_Downlink (protocol/landscape.options)"),
    ("core__enc", "their encodings", "2 x LS_DOWNLINK_MAX"),
    ("core__logs", "event and fault logs", "LS_EVENT_LOG_LEN, LS_FAULT_LOG_LEN"),
    ("core__sensor", "manual control and its reachability check", "one ls_motion_seg_t"),
    ("core__rest", "rest of the core", "RSVPs, DIO watches, settings, tool"),
    ("net", "`ls_net_t` (g_net)", ""),
    ("net__isotp", "ISO-TP links, one per peer", "LS_NET_MAX_PEERS x ls_isotp_link_t ({isotp_link} B: 2 x "
     "LS_ISOTP_MAX_PAYLOAD)"),
    ("net__outq", "downlink queues", "LS_NET_MAX_PEERS x LS_NET_OUTQ x ls_net_msg_t ({net_msg} B: LS_DOWNLINK_MAX)"),
    ("net__rxbuf", "reception buffer", "LS_ISOTP_MAX_PAYLOAD"),
    ("net__rest", "rest of the network layer", "links, buckets, counters"),
    ("ctl", "`ls_control_t` (g_ctl)", ""),
    ("ctl__rings", "command and event rings", "2 x LS_CTL_QUEUE_LEN"),
    ("ctl__motion", "plan slot and path executor", "2 x ls_motion_seg_t and the executor's state"),
    ("ctl__react", "plan slot and sensor-guided executor", "ls_react_plan_t, ls_react_t"),
    ("ctl__rest", "rest of the control loop", "snapshot, sensors, set-points"),
]
LIMIT_RE = re.compile(r"\b(LS_[A-Z_]+)\b")


def ram_parts(sizes_nm: str) -> tuple[dict[str, int], dict[str, int]]:
    """Sizes (fp_<name>) and limit values (fp_limit_<LIMIT>) from `arm-none-eabi-nm -S` of fw_sizes.o."""
    sizes: dict[str, int] = {}
    limits: dict[str, int] = {}
    for line in sizes_nm.splitlines():
        parts = line.split()
        if len(parts) != 4 or not parts[3].startswith("fp_"):
            continue
        value, name = int(parts[1], 16), parts[3][3:]
        if name.startswith("limit_"):
            limits[name[6:]] = value
        else:
            sizes[name] = value
    missing = [p for p, _, _ in RAM_PARTS if p not in sizes]
    if missing:
        raise BenchError(f"bench/footprint/fw_sizes.c does not measure {', '.join(missing)}: keep it and RAM_PARTS in "
                         "bench/b_footprint.py together")
    return sizes, limits


def ram_table(profiles: list[tuple[str, dict[str, int], dict[str, int]]]) -> str:
    """The static RAM table, one column per profile; each limit in the 'set by' column with its values."""
    head = "| part | " + " | ".join(f"{name} B" for name, _, _ in profiles) + " | set by |"
    rule = "|---|" + "---:|" * len(profiles) + "---|"
    lines = [head, rule]
    for key, what, setter in RAM_PARTS:
        text = setter.format(**{k: "/".join(str(s[k]) for _, s, _ in profiles)
                                for k in ("path_point", "motion_seg", "session", "isotp_link", "net_msg")})

        def with_values(m: re.Match[str]) -> str:
            vals = [lim.get(m.group(1)) for _, _, lim in profiles]
            return m.group(1) if None in vals else f"{m.group(1)} ({'/'.join(str(v) for v in vals)})"

        text = LIMIT_RE.sub(with_values, text)
        indent = "" if "__" not in key else "&nbsp;&nbsp;"
        name = what if "__" in key else f"**{what}**"
        lines.append(f"| {indent}{name} | " + " | ".join(str(s[key]) for _, s, _ in profiles) + f" | {text} |")
    return "\n".join(lines)


@dataclass
class Image:
    """One Cortex-M4F image of a profile: its size, symbols, linker map and static RAM parts."""

    text: int
    data: int
    bss: int
    syms: list[str]
    map_text: str
    firmware_allocs: set[str]
    sizes: dict[str, int]
    limits: dict[str, int]
    parts_map_text: str  # the map of the same objects linked without LTO (the per-part table)
    flash_without_lto: int


def build_image(targets: list[FwTarget], npb: Path | None, sodium: Path | None, defines: list[str],
                tmp: Path) -> Image:
    """Cross-compile and link the firmware's portable libraries + fw_main.c with `defines` added to every
    unit (a profile's), and measure the static RAM parts with fw_sizes.c under the same flags."""
    all_includes = list(dict.fromkeys(p for t in targets for p in t.includes))
    main_t = FwTarget("fw_main", [ROOT / "bench" / "footprint" / "fw_main.c"], all_includes)
    libs = []
    if npb is not None:
        libs.append(FwTarget("nanopb runtime", [npb / f for f in NANOPB_RUNTIME]))
    if sodium is not None:
        inc = sodium / SODIUM_INCLUDE
        libs.append(FwTarget("libsodium", [sodium / f for f in SODIUM_SOURCES], [inc / "sodium"], SODIUM_DEFINES))
    units = [(t, src) for t in [*targets, *libs, main_t] for src in t.sources]
    if any(src.suffix in CXX_SUFFIXES for _, src in units) and shutil.which(CXX) is None:
        raise BenchError(f"{CXX} is missing for the C++ sources: apt-get install gcc-arm-none-eabi")
    jobs = [(t, src, tmp / f"{i:02d}_{obj_stem(src)}.o") for i, (t, src) in enumerate(units)
            if src.suffix in CXX_SUFFIXES or src.suffix == ".c"]  # headers listed as sources are skipped
    sizes_job = (FwTarget("fw_sizes", [], all_includes), ROOT / "bench" / "footprint" / "fw_sizes.c",
                 tmp / "fw_sizes.o")

    def compile_one(job: tuple[FwTarget, Path, Path]) -> str:
        t, src, obj = job
        cmd = [CXX, *CXXFLAGS] if src.suffix in CXX_SUFFIXES else [CC, *CFLAGS]
        if obj != sizes_job[2]:
            cmd += LTO
        includes = [*([npb] if npb is not None else []), *([sodium / SODIUM_INCLUDE] if sodium is not None else []),
                    *t.includes]
        cc = run([*cmd, *t.options, *(f"-D{d}" for d in [*t.defines, *defines]), *(f"-I{p}" for p in includes),
                  "-c", str(src), "-o", str(obj)])
        return "" if cc.returncode == 0 else f"cross-compiling {src.name} ({t.name}) failed: " + \
            cc.stderr.strip()[-300:]

    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        errors = [e for e in pool.map(compile_one, [*jobs, sizes_job]) if e]
    if errors:
        raise BenchError("; ".join(errors))
    objs, firmware_allocs = [obj for _, _, obj in jobs], set()
    for _, src, obj in jobs:
        undefined = set(run(["arm-none-eabi-nm", "-u", str(obj)]).stdout.split()) - {"U"}
        if "fw_main" not in obj.name and "libsodium" not in str(src):
            # libsodium's utils.c has sodium_malloc: what counts is whether the image links an allocator (7c)
            firmware_allocs |= {f"{src.name}: {s}" for s in undefined & ALLOCATORS}
    elf, mapf = tmp / "fw.elf", tmp / "fw.map"
    ld = run([CC, *CFLAGS, *LTO, *LDFLAGS, *map(str, objs), f"-Wl,-Map={mapf}", "-o", str(elf), "-lm"])
    if ld.returncode != 0:
        raise BenchError(f"linking the Cortex-M4F image failed: {ld.stderr.strip()[-400:]}")
    parts_elf, parts_map = tmp / "fw-parts.elf", tmp / "fw-parts.map"
    ld = run([CC, *CFLAGS, "-fno-lto", *LDFLAGS, *map(str, objs), f"-Wl,-Map={parts_map}", "-o", str(parts_elf),
              "-lm"])
    if ld.returncode != 0:
        raise BenchError(f"linking the Cortex-M4F image without LTO failed: {ld.stderr.strip()[-400:]}")
    parts_text, parts_data = (int(x) for x in
                              run(["arm-none-eabi-size", str(parts_elf)]).stdout.splitlines()[1].split()[:2])
    text, data, bss = (int(x) for x in run(["arm-none-eabi-size", str(elf)]).stdout.splitlines()[1].split()[:3])
    syms = run(["arm-none-eabi-nm", "-S", "--size-sort", str(elf)]).stdout.splitlines()
    sizes, limits = ram_parts(run(["arm-none-eabi-nm", "-S", str(sizes_job[2])]).stdout)
    return Image(text, data, bss, syms, mapf.read_text(), firmware_allocs, sizes, limits, parts_map.read_text(),
                 parts_text + parts_data)


def bench_footprint(quick: bool) -> Section:
    del quick
    sec = Section(7, "Footprint on a Cortex-M4F (arm-none-eabi-gcc -Os, newlib-nano)")
    if shutil.which(CC) is None:
        raise BenchError("arm-none-eabi-gcc is missing: apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi")
    targets, libraries, profiles = read_manifest(MANIFEST)
    missing = [str(src) for t in targets for src in t.sources if not src.is_file()]
    if missing:
        raise BenchError(f"sources missing (generated ones are made by the bench build): {', '.join(missing)}; "
                         "build with bench/run.py first")
    npb = nanopb_runtime() if "nanopb::protobuf-nanopb-static" in libraries else None
    sodium = sodium_sources() if "PkgConfig::SODIUM" in libraries else None
    with tempfile.TemporaryDirectory(prefix="lsbench-fp-") as tmpdir:
        (Path(tmpdir) / "mcu").mkdir()
        (Path(tmpdir) / "linux").mkdir()
        img = build_image(targets, npb, sodium, profiles["mcu"], Path(tmpdir) / "mcu")
        ref = build_image(targets, npb, sodium, profiles["linux"], Path(tmpdir) / "linux")
    text, data, bss, syms, firmware_allocs = img.text, img.data, img.bss, img.syms, img.firmware_allocs
    linked_allocs = sorted({line.split()[-1] for line in syms} & ALLOCATORS)
    why = re.findall(r"\((lib_a-[\w-]+\.o)\)\s*\n?\s+\S*\((lib_a-[\w-]+\.o)\) "
                     r"\((_(?:malloc|realloc|free|calloc)_r|malloc|free|calloc)\)", img.map_text)
    breakdown: dict[str, dict[str, int]] = defaultdict(lambda: {"flash": 0, "ram": 0})
    for path, sizes in map_breakdown(img.parts_map_text).items():
        for k, v in sizes.items():
            breakdown[label(path)][k] += v
    big_ram = [line.split() for line in syms if line.split()[2] in "bBdD"][-4:]
    flash, ram = text + data, data + bss
    ref_flash, ref_ram = ref.text + ref.data, ref.data + ref.bss

    def goal(value: int, limit_kib: int) -> str:
        diff = value - limit_kib * 1024
        return (f"goal <= {limit_kib} KiB: met, {-diff / 1024:.1f} KiB to spare" if diff <= 0
                else f"goal <= {limit_kib} KiB: missed by {diff / 1024:.1f} KiB")

    reference = "linux profile (landscaped's limits), same sources"
    sec.rows.append(Row("7a. flash (text + data), mcu profile", f"{flash / 1024:.1f} KiB ({flash} B)", reference,
                        f"{ref_flash / 1024:.1f} KiB", f"{flash / ref_flash:.2f}",
                        f"{goal(flash, FLASH_GOAL_KIB)}; portable firmware + nanopb + newlib-nano"))
    sec.rows.append(Row("7b. RAM (data + bss), static, mcu profile", f"{ram / 1024:.1f} KiB ({ram} B)", reference,
                        f"{ref_ram / 1024:.1f} KiB", f"{ram / ref_ram:.3f}",
                        f"{goal(ram, RAM_GOAL_KIB)}; largest: " +
                        ", ".join(f"{s[3]} {int(s[1], 16)} B" for s in reversed(big_ram))))
    heap = ("no firmware object references an allocator" if not firmware_allocs
            else "firmware objects reference: " + ", ".join(sorted(firmware_allocs)))
    pulled = sorted({f"{b} -> {sym}" for _, b, sym in why}) or []
    sec.rows.append(Row("7c. heap, mcu profile", heap, "allocator symbols in the image (arm-none-eabi-nm)",
                        ", ".join(linked_allocs) or "none", "",
                        ("goal none: missed; pulled in by " + "; ".join(pulled) +
                         "; _sbrk stubbed to fail: no heap region")
                        if linked_allocs else "goal none: met, no allocator in the image"))
    sec.details.append(
        f"`{CC} {' '.join(CFLAGS)} {' '.join(LTO)}` (C++: `{CXX} {' '.join(CXXFLAGS)} {' '.join(LTO)}`), linked "
        f"with `{' '.join(LDFLAGS)} -lm`; link-time optimisation takes {(img.flash_without_lto - flash) / 1024:.1f} "
        f"KiB off the {img.flash_without_lto / 1024:.1f} KiB of the same objects linked without it. Sources: "
        "every library `landscaped` links, followed through their link "
        "libraries, except the OS parts (the targets under firmware/app, hal/sim, hal/linux); bench/CMakeLists.txt "
        "computes that list from the main build's targets and writes it with each target's include directories, "
        "definitions and -f options to build-bench/footprint/portable.txt, so the image compiles the same "
        f"sources as the firmware. Here: {', '.join(t.name for t in targets)}. The nanopb runtime "
        f"({npb.name if npb is not None else 'not linked'}: pb_encode.c, pb_decode.c, pb_common.c) comes from "
        "Debian's source package (the PyPI `nanopb` sdist/wheel ship only the generator, libnanopb-dev only an x86 "
        "archive). `bench/footprint/fw_main.c` is landscaped's composition without the OS (core + net on one CAN "
        "link, the control loop on a 1 ms tick with its events drained into the core, the heartbeat, one "
        "trajectory plan and sample per turn), CAN and arm HALs as volatile registers, an entry point that zeroes "
        ".bss, and an `_sbrk` that always fails (should an allocator be linked again). Not included: the sim and "
        "Linux HAL backends, telemetry "
        "broadcasts, landscaped's "
"process glue, a board's vector table and linker script. -DNDEBUG as in a release build. "
        "The image is built twice from the same sources: with the mcu profile's definitions "
        f"({' '.join('-D' + d for d in profiles['mcu'])}: the limits for a 256 KiB-RAM Cortex-M4F, CMakeLists.txt "
        "LS_PROFILE) and, for reference, with the linux profile's (what landscaped and the tests run); the rows, the "
        "per-part table and the heap check are the mcu image's.")
    rows = sorted(breakdown.items(), key=lambda kv: -(kv[1]["flash"] + kv[1]["ram"]))
    if flash > FLASH_GOAL_KIB * 1024:
        code = sorted(((k, v["flash"]) for k, v in breakdown.items()), key=lambda kv: -kv[1])[:5]
        sec.details.append(
            f"Flash: the goal (<= {FLASH_GOAL_KIB} KiB) is missed by {(flash - FLASH_GOAL_KIB * 1024) / 1024:.1f} KiB. "
            "The largest parts: " + ", ".join(f"{k} {v / 1024:.1f} KiB" for k, v in code) + ". Everything computes "
            "in double, which the Cortex-M4F's single-precision FPU runs as calls into libgcc and newlib's libm; "
            "the core's share is mostly its handlers and the texts of their answers.")
    sec.details.append("Per part (from the map of the same objects linked without LTO, "
                       f"{img.flash_without_lto} B of flash; flash includes initialised data):\n\n"
                       "| part | flash B | RAM B |\n|---|---:|---:|\n" +
                       "\n".join(f"| {k} | {v['flash']} | {v['ram']} |" for k, v in rows))
    sec.details.append("Where the static RAM goes (`bench/footprint/fw_sizes.c`: each part's size as the target "
                       "compiler lays it out, and the limits that set it):\n\n" +
                       ram_table([("mcu", img.sizes, img.limits), ("linux", ref.sizes, ref.limits)]))
    if linked_allocs:
        sec.details.append(
            "Heap: the firmware's own objects reference no allocator (checked with `arm-none-eabi-nm -u` on each "
            "object). The allocator comes from newlib-nano itself: `vsnprintf` (the core formats answers with it) "
            "references `_realloc_r` for its growing-string mode (`asprintf`), which a fixed-buffer `snprintf` "
            "never takes, and `strtod` (firmware/core/cmd_aux.c) uses gdtoa's big-number helpers, which call "
            "`_calloc_r`/`_malloc_r` for long inputs and can reach `__assert_func` -> `fiprintf` -> stdio (hence the "
            "nosys stubs). With `_sbrk` failing, that code can never obtain memory (strtod then fails on such input). "
            "To have no allocator in the image at all, the core would need its own formatter and number parser.")
    else:
        sec.details.append(
            "Heap: none. The firmware formats and parses with `firmware/common/ls_fmt.c` (fixed buffers, no stdio), "
            "not newlib's `vsnprintf` and `strtod`, which linked newlib's allocator; `arm-none-eabi-nm` of the image "
            f"shows none of {', '.join(sorted(ALLOCATORS))}, and the firmware's objects reference none "
            "(`arm-none-eabi-nm -u` on each). The image links without newlib's system-call stubs (no nosys.specs).")
    mcu_defs = " ".join(f"-D{d}" for d in profiles["mcu"])
    sec.commands.append(f"{CC} {' '.join(CFLAGS)} {' '.join(LTO)} {mcu_defs} -I... <sources> {' '.join(LDFLAGS)} "
                        "-Wl,-Map=fw.map -o fw.elf -lm")
    sec.commands.append("arm-none-eabi-size fw.elf; arm-none-eabi-nm fw.elf | grep -E ' (malloc|free|_sbrk)'")
    return sec
