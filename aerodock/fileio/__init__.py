"""Files: atomic writes of files and folders (:mod:`~aerodock.fileio.writes`), strict JSON
(:mod:`~aerodock.fileio.jsonio`), and inputs read as regular files of bounded size, TOML and
guarded ``.npz`` headers (:mod:`~aerodock.fileio.inputs`). Every name is importable from here.
"""

from aerodock.fileio.inputs import (
    MAX_CSV_BYTES,
    MAX_JSON_BYTES,
    MAX_NPZ_BYTES,
    MAX_TOML_BYTES,
    READ_ERRORS,
    InputError,
    check_input_file,
    check_npz_header,
    check_npz_sizes,
    npz_int,
    one_line,
    open_input,
    read_input_bytes,
    read_input_text,
    read_toml,
)
from aerodock.fileio.jsonio import dumps_json, json_default, json_ready, write_json
from aerodock.fileio.writes import (
    LEGACY_DIR_TEMP_AGE_S,
    atomic_open,
    building_dir,
    check_output_dir,
    check_writable_target,
    glob_escape,
    refuse_symlink,
    remove_stale_build_dirs,
    remove_stale_dir_temps,
    remove_stale_temps,
    swap_in_dir,
    write_dir_atomic,
)

__all__ = [
    "LEGACY_DIR_TEMP_AGE_S", "MAX_CSV_BYTES", "MAX_JSON_BYTES", "MAX_NPZ_BYTES", "MAX_TOML_BYTES",
    "READ_ERRORS", "InputError", "atomic_open", "building_dir", "check_input_file",
    "check_npz_header", "check_npz_sizes", "check_output_dir", "check_writable_target",
    "dumps_json", "glob_escape", "json_default", "json_ready", "npz_int", "one_line",
    "open_input", "read_input_bytes", "read_input_text", "read_toml", "refuse_symlink",
    "remove_stale_build_dirs", "remove_stale_dir_temps", "remove_stale_temps", "swap_in_dir",
    "write_dir_atomic", "write_json",
]
