#!/usr/bin/env python3
"""The annotated frames of docs/protocol.md, computed independently of the Rust encoder:
postcard by hand (varints, f32 little-endian), zlib.crc32, a hand-written COBS."""
import struct, zlib
def cobs(data):
    out=bytearray(); i=0
    block=bytearray()
    for b in data:
        if b==0:
            out.append(len(block)+1); out+=block; block=bytearray()
        else:
            block.append(b)
            if len(block)==254:
                out.append(255); out+=block; block=bytearray()
    out.append(len(block)+1); out+=block
    return bytes(out)
def frame(payload):
    crc=zlib.crc32(payload)&0xffffffff
    return cobs(payload+struct.pack('<I',crc))+b'\x00', crc
f32=lambda x: struct.pack('<f',x)
def varint(v):
    out=bytearray()
    while True:
        low=v&0x7f; v>>=7
        if v==0:
            out.append(low); return bytes(out)
        out.append(low|0x80)
V=8  # PROTOCOL_VERSION
req=bytes([V,5,0,0x0b])
w,crc=frame(req); print('req', w.hex(' '), hex(crc))
p=bytes([V,5,1,6, 1,1,0,0,0])+f32(2e-6)+f32(3e-7)+f32(4e-6)+bytes([0])
p+=bytes([1])+f32(2.2e-6)+f32(3.2e-7)+f32(-2.1)+f32(3.3e-6)+bytes([7])
p+=bytes([1])+f32(1.5e-5)+f32(-2.5e-6)+bytes([0])+bytes([1])
# v6: frequency_hz f32, options {track Z=1, headroom f32}, tracking_error_hz Some(-0.5), locked true
p+=f32(20100.0)+bytes([1])+f32(2.0)+bytes([1])+f32(-0.5)+bytes([1])
# v8: cpu_load_pct Some(12.5), cpu_load_max_pct Some(28.75)
p+=bytes([1])+f32(12.5)+bytes([1])+f32(28.75)
print('payload', p.hex(' '))
w,crc=frame(p); print('resp', w.hex(' '), hex(crc))
print(', '.join('0x%02x'%b for b in w))
# v7: Info.self_test = SelfTest { ran: ALL (0x3f), failed: HSE_FREQUENCY | STREAMS_RUNNING (0x22),
# hse_hz: 12 000 000, sysclk_hz: 168 000 000 } (four varints)
st=varint(0x3f)+varint(0x22)+varint(12_000_000)+varint(168_000_000)
print('self_test', st.hex(' '))
