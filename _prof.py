import numpy as np, curv, time, cProfile, pstats
p=np.random.default_rng(0).normal(size=(100000,3)); p/=np.linalg.norm(p,axis=1,keepdims=True)
curv.estimate(curv.PointCloud(p[:500]), "mru", 2)
pr=cProfile.Profile(); pr.enable()
t=time.perf_counter(); r=curv.estimate(curv.PointCloud(p), "mru", 2); print('total', time.perf_counter()-t)
pr.disable(); pstats.Stats(pr).sort_stats('cumtime').print_stats(25)
