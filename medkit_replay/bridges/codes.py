"""Fault-code derivation shared by the bridges: upper-snake folding, hashes and length bounds.

Byte-exact with upstream 0.6.0 (bridges.md §1.5, §2.3, §3.2), including libstdc++'s string hash.
"""

from __future__ import annotations

import re

_MASK64 = (1 << 64) - 1
_MURMUR_MUL = 0xC6A4A7935BD1E995
_LIBSTDCXX_SEED = 0xC70F6907
_FNV32_OFFSET = 0x811C9DC5
_FNV32_PRIME = 0x01000193

_NON_ALNUM_RUN = re.compile(rb"[^A-Za-z0-9]+")
_NON_ALPHA_RUN = re.compile(rb"[^A-Za-z]+")

MAX_CODE_LEN = 64
ACTION_PART_BUDGET = 48
_HASH_TAG_LEN = 5  # "_" + four hex digits
_LONGEST_STATUS_SUFFIX = len("_CANCELED")
LOG_NODE_BUDGET = 48
LOG_PREFIX_BUDGET = 32
NO_MESSAGE_TEMPLATE = "_NOMSG"


def _utf8(text: str) -> bytes:
    # Upstream walks the raw bytes of std::string; surrogatepass never raises on odd input.
    return text.encode("utf-8", "surrogatepass")


def upper_snake(text: str) -> str:
    """Fold to ``[A-Z0-9_]``: ASCII alnum upper-cased, every other byte run becomes one ``_``.

    Leading and trailing separators vanish; no length bound (the diagnostic bridge's codes).
    """
    folded = _NON_ALNUM_RUN.sub(b"_", _utf8(text)).strip(b"_")
    return folded.upper().decode("ascii")


def truncate_code(code: str, max_len: int) -> str:
    """Cut to ``max_len`` and drop the ``_`` left dangling (the log bridge's bound)."""
    return code[:max_len].rstrip("_") if len(code) > max_len else code


def hash_bounded(code: str, max_len: int) -> str:
    """Bound ``code`` to ``max_len``, ending in a 4-hex tag of its full text (action bridge).

    The tag is the low 16 bits of libstdc++'s ``std::hash<std::string>`` (bridges.md §1.5 step 3),
    so names sharing a long common head still get distinct codes.
    """
    if len(code) <= max_len:
        return code
    keep = max_len - _HASH_TAG_LEN if max_len > _HASH_TAG_LEN else 0
    tag = libstdcxx_string_hash(code.encode("ascii")) & 0xFFFF
    return f"{code[:keep].rstrip('_')}_{tag:04X}"


def _shift_mix(value: int) -> int:
    return value ^ (value >> 47)


def libstdcxx_string_hash(data: bytes, seed: int = _LIBSTDCXX_SEED) -> int:
    """``std::hash<std::string>`` of 64-bit libstdc++ (``_Hash_bytes``, a MurmurHash64A variant)."""
    length = len(data)
    state = seed ^ ((length * _MURMUR_MUL) & _MASK64)
    whole = length - length % 8
    for offset in range(0, whole, 8):
        block = int.from_bytes(data[offset : offset + 8], "little")
        block = (_shift_mix((block * _MURMUR_MUL) & _MASK64) * _MURMUR_MUL) & _MASK64
        state = ((state ^ block) * _MURMUR_MUL) & _MASK64
    if whole < length:
        tail = int.from_bytes(data[whole:], "little")
        state = ((state ^ tail) * _MURMUR_MUL) & _MASK64
    state = (_shift_mix(state) * _MURMUR_MUL) & _MASK64
    return _shift_mix(state)


def fnv1a32_hex(text: str) -> str:
    """FNV-1a 32-bit over the UTF-8 bytes, as eight lowercase hex digits."""
    value = _FNV32_OFFSET
    for byte in _utf8(text):
        value = ((value ^ byte) * _FNV32_PRIME) & 0xFFFFFFFF
    return f"{value:08x}"


# --- action status bridge (bridges.md §1.5) ---


def action_code_prefix(raw: str) -> str:
    """``code_prefix`` as the action bridge normalises it; ``""`` means "fall back to ACTION"."""
    return hash_bounded(upper_snake(raw), ACTION_PART_BUDGET)


def action_fault_code(prefix: str, action_name: str, *, canceled: bool) -> str:
    """``<PREFIX>_<ACTION>_ABORTED`` or ``_CANCELED``, at most 64 characters."""
    suffix = "_CANCELED" if canceled else "_ABORTED"
    fixed = len(prefix) + 1 + _LONGEST_STATUS_SUFFIX + 1
    budget = ACTION_PART_BUDGET
    if fixed + budget > MAX_CODE_LEN:
        budget = max(MAX_CODE_LEN - fixed, 0)
    part = hash_bounded(upper_snake(action_name), budget)
    code = f"{prefix}_{part}{suffix}" if part else f"{prefix}{suffix}"
    return truncate_code(code, MAX_CODE_LEN)


# --- log bridge (bridges.md §3.2) ---


def log_code_prefix(raw: str) -> str:
    """``code_prefix`` as the log bridge normalises it (no hash tag); empty → ``LOG``."""
    return truncate_code(upper_snake(raw), LOG_PREFIX_BUDGET) or "LOG"


def log_message_template(message: str) -> str:
    """Lower-case ASCII words of ``message``; digits, punctuation and one-letter words dropped."""
    letters = _NON_ALPHA_RUN.sub(b" ", _utf8(message)).lower().decode("ascii")
    return " ".join(word for word in letters.split() if len(word) > 1)


def log_fault_code(prefix: str, source_id: str, message: str) -> str:
    """``<PREFIX>_<NODE>_<hash>``: the hash of the message template always survives the bound."""
    digest = fnv1a32_hex(log_message_template(message) or NO_MESSAGE_TEMPLATE)
    fixed = len(prefix) + 2 + len(digest)
    if fixed >= MAX_CODE_LEN:
        return f"{prefix}_{digest}"
    node = truncate_code(
        truncate_code(upper_snake(source_id), LOG_NODE_BUDGET), MAX_CODE_LEN - fixed
    )
    return f"{prefix}_{node}_{digest}" if node else f"{prefix}_{digest}"
