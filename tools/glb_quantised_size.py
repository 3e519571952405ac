# Bytes a float stand export (`sylva export --no-quantize`, or a file of round 45 and before) would
# take written by round 46's quantisation rules (src/output/gltf.rs, `Doc::primitive_q`), counted per
# primitive from its JSON: positions 8 B, normals 4 B (none for leaf and cluster cards with
# --drop-card-normals, the writer's DROP_FLAT_CARD_NORMALS, off), card and bark
# texture coordinates 4 B, indices 2 B where a primitive has at most 65,535 vertices.
# Usage: python3 tools/glb_quantised_size.py STAND.glb
import json,struct,sys
DROP = '--drop-card-normals' in sys.argv  # DROP_FLAT_CARD_NORMALS (off in the writer)
f=open(sys.argv[1],'rb'); f.read(12); l,t=struct.unpack('<II',f.read(8)); js=json.loads(f.read(l))
acc=js['accessors']; mats=js['materials']
orig=0; new=0; big=0; n_prims=0; by={}
pad=lambda x:(x+3)//4*4
for m in js['meshes']:
  for p in m['primitives']:
    kind=mats[p['material']]['name'].split('_')[-1]
    a=p['attributes']; n=acc[a['POSITION']]['count']; ni=acc[p['indices']]['count']
    o=n*12+(n*12 if 'NORMAL' in a else 0)+(n*8 if 'TEXCOORD_0' in a else 0)+ni*4
    if kind=='terrain':
      q=o
    else:
      cards = kind in ('leaf','cluster','impostor')
      q=n*8+(0 if (cards and DROP) else n*4)+(n*4 if 'TEXCOORD_0' in a else 0)+pad(ni*(2 if n<=65535 else 4))
      if n>65535: big+=1
    orig+=o; new+=q; n_prims+=1
    b=by.setdefault(kind,[0,0]); b[0]+=o; b[1]+=q
img=js['buffers'][0]['byteLength']-orig
print('primitives',n_prims,'over 65535 verts',big)
print('vertex+index bytes: floats %.1f MB -> quantised %.1f MB'%(orig/1e6,new/1e6))
print('file: %.1f MB -> %.1f MB (ratio %.2f)'%((orig+img+l)/1e6,(new+img+l)/1e6,(orig+img+l)/(new+img+l)))
for k,(o,q) in by.items(): print(k,'%.1f -> %.1f MB'%(o/1e6,q/1e6))
