#!/usr/bin/python3
"""drift_map: where along a belt-front run the particles drift apart from their densities.

  tools/drift_map.py RUN_DIR SNAPSHOT.vtp [SNAPSHOT.vtp ...]

For each snapshot (file names inside RUN_DIR), in 2 cm columns from the upstream wall (x = 0.012 m) to the toe:
the mean of (kernel-summed density) / (particle density) over fluid particles with full kernel support (more than
2h below the column's top particle), separately in the lower 35 % ("l") and the rest ("h") of that depth.
1 means the spacing matches the densities (see tools/operator_check.py). Reads params.ini; numpy only.
"""
import os
import sys, math, numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import vtp  # noqa: E402
if len(sys.argv) < 3:
    sys.exit(__doc__)
run=sys.argv[1]; files=sys.argv[2:]
txt=open(run+"/params.ini").read()
dp=float(txt.split("dp_m = ")[1].split()[0]); ch=float(txt.split("\nch = ")[1].split()[0]); m=1383*dp*dp
L=float(txt.split("length_m = ")[1].split()[0]); h=ch*math.sqrt(2)*dp; aD=7/(4*math.pi*h*h)
for f in files:
    s=vtp.read_vtp(run+"/"+f); x=s["points"][:,0]; y=s["points"][:,1]; k=s["kind"]; rho=s["density_kgpm3"]
    fl=np.where(k==0)[0]
    toe=x[fl].max()
    edges=np.arange(0.012, toe+0.02, 0.02)
    row=[]
    for a0,a1 in zip(edges[:-1],edges[1:]):
        col=fl[(x[fl]>=a0)&(x[fl]<a1)]
        if len(col)==0: continue
        top=y[col].max()
        for lo,hi,name in ((0,0.35,"low"),(0.35,1,"high")):
            sel=col[(y[col]<top-2*h)&(y[col]>=lo*(top-2*h))&(y[col]<hi*(top-2*h))]
            r=[]
            for a in sel:
                dx=x[a]-x; dx-=L*np.round(dx/L); q=np.hypot(dx,y[a]-y)/h; n=q<2
                r.append(np.sum(m*aD*(1-q[n]/2)**4*(2*q[n]+1))/rho[a])
            row.append("%s%.3f" % (name[0], np.mean(r)) if r else "%s  -  " % name[0])
        row[-2]="x%.2f:" % a0 + row[-2]
    print("t=%.1f toe %.3f:" % (s["time_s"], toe), " ".join(row))
