"""Semi-analytical (boundary-integral) walls: the kernel's wall share and its moments.

``share.wall_terms`` gives, for every particle, the wall share s = int_outside W, its
gradient G = grad s and the hydrostatic moment T g of a convex domain of planes, exactly
(closed forms, any corner angle, 2D and 3D); Kulasegaram et al. (2004), Feldman & Bonet
(2007), Ferrand et al. (2013), Mayrhofer et al. (2015). The plugin class that adds
-(2 p G + rho T g)/(gamma rho) to the momentum and rho v.G to the continuity equation,
with gamma = 1 - s, is written separately.
"""
