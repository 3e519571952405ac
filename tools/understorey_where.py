#!/usr/bin/env python3
"""Under which stands the suppressed old oaks stand (issue 35, round 41): of the living sessile
oaks aged > 60 years and under 10 m, the basal area (m²/ha) of the 3 x 3 light cells (15 m) around
their cell, and the species that leads that block's basal area (with how many stand where it holds
>= 70 %). The 480 x 360 grid of 5 m cells is the default run's (2400 m x 1800 m).

Usage: python3 tools/understorey_where.py RUN/inventory/year_0150.parquet  (needs pyarrow, pandas, numpy)
"""
import sys, numpy as np, pyarrow.parquet as pq
t=pq.read_table(sys.argv[1],columns=['species','x_m','y_m','height_m','dbh_cm','age_yr','status']).to_pandas()
t=t[t.status=='alive'].reset_index(drop=True)
cell=5.0; cols=480; rows=360
c=np.clip((t.y_m//cell).astype(int),0,rows-1)*cols+np.clip((t.x_m//cell).astype(int),0,cols-1)
ba=np.pi*(t.dbh_cm/200)**2
sps=sorted(t.species.unique())
B=np.zeros((len(sps),rows,cols))
for k,s in enumerate(sps):
    B[k]=np.bincount(c[t.species==s],ba[t.species==s],rows*cols).reshape(rows,cols)
N=np.zeros_like(B)
for dx in (-1,0,1):
  for dy in (-1,0,1):
    N+=np.roll(np.roll(B,dx,1),dy,2)
tot=N.sum(0); ha=9*25/1e4
s=t[(t.species=='sessile_oak')&(t.age_yr>60)&(t.height_m<10)]
cc=c[s.index]
r,q=cc//cols,cc%cols
dom=np.argmax(N[:,r,q],0); share=N[dom,r,q]/np.maximum(tot[r,q],1e-9)
bah=tot[r,q]/ha
import collections
print('suppressed oaks',len(s),'block BA median',np.median(bah).round(1),'share of them in blocks with BA>=30:',(bah>=30).mean().round(3))
for k in np.argsort(-np.bincount(dom,minlength=len(sps))):
    m=dom==k
    if m.sum()==0: continue
    print(f'  dominant {sps[k]:<14} {m.sum():>6} ({m.mean():.3f}), of which >=70% BA share {((share>=0.7)&m).sum()}')
