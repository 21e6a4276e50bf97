"""LZF (Marc Lehmann's format, as PCL writes binary_compressed PCD bodies): compress and decompress.

Used by make_seeds.py and shared_data_seeds.py to write binary_compressed PCD seeds. The stream is
a sequence of chunks: a control byte c < 32 is followed by c + 1 literal bytes; otherwise
len = c >> 5 (7 means: add the next byte) and the back reference copies len + 2 bytes starting
((c & 31) << 8) + next byte + 1 bytes behind the end of the output.
"""

MAX_LITERAL = 32
MAX_OFFSET = 8191
MAX_MATCH = 7 + 255 + 2


def compress(data: bytes) -> bytes:
    """Greedy LZF compression with a 3-byte hash of the last position, as short as it is simple."""
    out = bytearray()
    literal = bytearray()
    last_seen = {}

    def flush_literal():
        while literal:
            run = literal[:MAX_LITERAL]
            out.append(len(run) - 1)
            out.extend(run)
            del literal[:MAX_LITERAL]

    position = 0
    while position < len(data):
        key = data[position:position + 3]
        candidate = last_seen.get(key) if len(key) == 3 else None
        if len(key) == 3:
            last_seen[key] = position
        if candidate is not None and position - candidate - 1 <= MAX_OFFSET:
            length = 0
            while (length < MAX_MATCH and position + length < len(data)
                   and data[candidate + length] == data[position + length]):
                length += 1
            if length >= 3:
                flush_literal()
                offset = position - candidate - 1
                encoded = length - 2
                if encoded < 7:
                    out.append((encoded << 5) | (offset >> 8))
                else:
                    out.append((7 << 5) | (offset >> 8))
                    out.append(encoded - 7)
                out.append(offset & 0xFF)
                position += length
                continue
        literal.append(data[position])
        position += 1
    flush_literal()
    return bytes(out)


def decompress(data: bytes, expected_size: int) -> bytes:
    """Decompresses an LZF stream; ValueError when it is corrupt or does not give expected_size bytes."""
    out = bytearray()
    position = 0
    while position < len(data):
        control = data[position]
        position += 1
        if control < 32:
            length = control + 1
            if position + length > len(data):
                raise ValueError("LZF literal run past the end of the input")
            out += data[position:position + length]
            position += length
            continue
        length = control >> 5
        if length == 7:
            length += data[position]
            position += 1
        if position >= len(data):
            raise ValueError("LZF back reference past the end of the input")
        reference = len(out) - ((control & 0x1F) << 8) - data[position] - 1
        position += 1
        length += 2
        if reference < 0:
            raise ValueError("LZF back reference before the start of the output")
        if reference + length <= len(out):
            out += out[reference:reference + length]
        else:
            for k in range(length):
                out.append(out[reference + k])
    if len(out) != expected_size:
        raise ValueError(f"LZF stream gives {len(out)} bytes, expected {expected_size}")
    return bytes(out)
