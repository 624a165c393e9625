# base-phong's tensors plus tiny-phong-colour's trained colour path (colour.up.0.*): the
# start of base-phong-colour. Raw safetensors: u64 header length, JSON header, data.
import json, struct, sys
def read(p):
    b = open(p, 'rb').read(); n = struct.unpack('<Q', b[:8])[0]
    h = json.loads(b[8:8 + n]); return h, b[8 + n:]
base, colour, out = sys.argv[1:4]
hb, db = read(base); hc, dc = read(colour)
meta = hb.pop('__metadata__', None); hc.pop('__metadata__', None)
tensors = {k: (v['dtype'], v['shape'], db[v['data_offsets'][0]:v['data_offsets'][1]]) for k, v in hb.items()}
for k in ('colour.up.0.weight', 'colour.up.0.bias'):
    v = hc[k]; tensors[k] = (v['dtype'], v['shape'], dc[v['data_offsets'][0]:v['data_offsets'][1]])
header, data, off = {}, b'', 0
for k in sorted(tensors):
    dt, sh, raw = tensors[k]; header[k] = {'dtype': dt, 'shape': sh, 'data_offsets': [off, off + len(raw)]}; data += raw; off += len(raw)
if meta: header['__metadata__'] = meta
hj = json.dumps(header).encode(); hj += b' ' * ((8 - len(hj) % 8) % 8)
open(out, 'wb').write(struct.pack('<Q', len(hj)) + hj + data)
print(out, len(tensors), 'tensors; metadata', meta)
