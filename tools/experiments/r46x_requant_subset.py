# Writes the first N trees of a float stand export as a float glb and as one quantised by round 46's
# rules (a format check for Blender and the validator while the branch's build runs).
import json, struct, sys, math
src, n_trees, out_f, out_q = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
f = open(src, 'rb'); f.read(12); l, _ = struct.unpack('<II', f.read(8)); js = json.loads(f.read(l)); f.read(8); base = f.tell()
def raw(view):
    v = js['bufferViews'][view]; f.seek(base + v['byteOffset']); return f.read(v['byteLength'])
def acc(a):
    A = js['accessors'][a]; nc = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3}[A['type']]; b = raw(A['bufferView'])
    fmt = 'f' if A['componentType'] == 5126 else 'I'
    d = struct.unpack('<%d%s' % (A['count'] * nc, fmt), b[:A['count'] * nc * 4]); return [d[i*nc:(i+1)*nc] for i in range(A['count'])]
trees_root = [n for n in js['nodes'] if n.get('name') == 'trees'][0]
tree_nodes = trees_root['children'][:n_trees]
def build(quant):
    out = {'asset': {'version': '2.0', 'generator': 'r46x requant.py'}, 'scene': 0, 'nodes': [], 'meshes': [], 'accessors': [], 'bufferViews': [], 'materials': [], 'textures': js['textures'], 'images': [], 'samplers': js['samplers']}
    binb = bytearray(); ext = set()
    def view(b, stride=None, target=None):
        while len(binb) % 4: binb.append(0)
        v = {'buffer': 0, 'byteOffset': len(binb), 'byteLength': len(b)}
        if stride: v['byteStride'] = stride
        if target: v['target'] = target
        binb.extend(b); out['bufferViews'].append(v); return len(out['bufferViews']) - 1
    def accessor(v, count, ct, ty, **kw):
        a = {'bufferView': v, 'count': count, 'componentType': ct, 'type': ty}; a.update(kw); out['accessors'].append(a); return len(out['accessors']) - 1
    for im in js['images']:
        out['images'].append({'bufferView': view(raw(im['bufferView'])), 'mimeType': im['mimeType'], 'name': im.get('name', '')})
    for m in js['materials']:
        m = json.loads(json.dumps(m))
        if quant and m['name'].endswith('_bark'):
            m['pbrMetallicRoughness']['baseColorTexture']['extensions'] = {'KHR_texture_transform': {'scale': [1/64, 1/64]}}; ext.add('KHR_texture_transform')
        out['materials'].append(m)
    mesh_map = {}; roots = []
    for ti in tree_nodes:
        tn = js['nodes'][ti]; kids = []
        for ci in tn.get('children', []):
            c = js['nodes'][ci]; mi = c['mesh']
            if mi not in mesh_map:
                M = js['meshes'][mi]; prims = []
                parts = [(p, acc(p['attributes']['POSITION'])) for p in M['primitives']]
                allp = [q for _, P in parts for q in P]
                lo = [min(q[k] for q in allp) for k in range(3)]; hi = [max(q[k] for q in allp) for k in range(3)]
                off = [(lo[k] + hi[k]) / 2 for k in range(3)]; sc = max(max((hi[k] - lo[k]) / 2 for k in range(3)), 1e-6)
                for p, P in parts:
                    kind = js['materials'][p['material']]['name'].split('_')[-1]
                    N = acc(p['attributes']['NORMAL']); U = acc(p['attributes']['TEXCOORD_0']); I = [i for t in acc(p['indices']) for i in t]
                    n = len(P); at = {}
                    if quant:
                        enc = [tuple(max(-32767, min(32767, round((q[k] - off[k]) / sc * 32767))) for k in range(3)) for q in P]
                        b = b''.join(struct.pack('<hhhh', *e, 0) for e in enc)
                        at['POSITION'] = accessor(view(b, 8, 34962), n, 5122, 'VEC3', normalized=True, min=[min(e[k] for e in enc) for k in range(3)], max=[max(e[k] for e in enc) for k in range(3)])
                        if True:  # the writer keeps the cards' normals (DROP_FLAT_CARD_NORMALS off)
                            b = b''.join(struct.pack('<bbbb', *[max(-127, min(127, round(c * 127))) for c in q], 0) for q in N)
                            at['NORMAL'] = accessor(view(b, 4, 34962), n, 5120, 'VEC3', normalized=True)
                        if kind == 'bark':
                            fl = [math.floor(min(u[k] for u in U)) for k in range(2)]
                            b = b''.join(struct.pack('<HH', *[round((u[k] - fl[k]) * 64) for k in range(2)]) for u in U)
                            at['TEXCOORD_0'] = accessor(view(b, 4, 34962), n, 5123, 'VEC2')
                        else:
                            b = b''.join(struct.pack('<HH', *[round(min(1, max(0, c)) * 65535) for c in u]) for u in U)
                            at['TEXCOORD_0'] = accessor(view(b, 4, 34962), n, 5123, 'VEC2', normalized=True)
                        if n <= 65535:
                            ia = accessor(view(struct.pack('<%dH' % len(I), *I), None, 34963), len(I), 5123, 'SCALAR')
                        else:
                            ia = accessor(view(struct.pack('<%dI' % len(I), *I), None, 34963), len(I), 5125, 'SCALAR')
                        ext.add('KHR_mesh_quantization')
                    else:
                        at['POSITION'] = accessor(view(struct.pack('<%df' % (3*n), *[c for q in P for c in q]), 12, 34962), n, 5126, 'VEC3', min=[min(q[k] for q in P) for k in range(3)], max=[max(q[k] for q in P) for k in range(3)])
                        at['NORMAL'] = accessor(view(struct.pack('<%df' % (3*n), *[c for q in N for c in q]), 12, 34962), n, 5126, 'VEC3')
                        at['TEXCOORD_0'] = accessor(view(struct.pack('<%df' % (2*n), *[c for q in U for c in q]), 8, 34962), n, 5126, 'VEC2')
                        ia = accessor(view(struct.pack('<%dI' % len(I), *I), None, 34963), len(I), 5125, 'SCALAR')
                    prims.append({'attributes': at, 'indices': ia, 'material': p['material'], 'mode': 4})
                out['meshes'].append({'name': M['name'], 'primitives': prims}); mesh_map[mi] = (len(out['meshes']) - 1, off, sc)
            mi2, off, sc = mesh_map[mi]
            node = {'name': c['name'], 'mesh': mi2}
            if quant: node['translation'] = off; node['scale'] = [sc] * 3
            out['nodes'].append(node); kids.append(len(out['nodes']) - 1)
        t = {k: v for k, v in tn.items() if k != 'children'}; t['children'] = kids; out['nodes'].append(t); roots.append(len(out['nodes']) - 1)
    out['nodes'].append({'name': 'trees', 'children': roots}); out['scenes'] = [{'nodes': [len(out['nodes']) - 1]}]
    if ext: out['extensionsUsed'] = sorted(ext); out['extensionsRequired'] = sorted(ext)
    while len(binb) % 4: binb.append(0)
    out['buffers'] = [{'byteLength': len(binb)}]
    j = json.dumps(out).encode();
    while len(j) % 4: j += b' '
    return b'glTF' + struct.pack('<II', 2, 28 + len(j) + len(binb)) + struct.pack('<I', len(j)) + b'JSON' + j + struct.pack('<I', len(binb)) + b'BIN\0' + bytes(binb)
open(out_f, 'wb').write(build(False)); open(out_q, 'wb').write(build(True))
