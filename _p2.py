import numpy as np, time, curv
from curv.validity import describe_reasons
rng=np.random.default_rng(1)
n=20000
p=rng.normal(size=(n,3)); p/=np.linalg.norm(p,axis=1)[:,None]
c=curv.PointCloud(p*2.0)
r=curv.estimate(c,"qs",2); print(describe_reasons(r.reason), r.info)
for nm in ("pca","fit"):
  for m in ("qs","nc","mru","an","jet"):
    r=curv.estimate(c,m,2, normals=nm)
    print(nm, m, np.nanmedian(r.k1), np.nanmedian(r.k2), np.nanpercentile(r.mean,[5,95]))
