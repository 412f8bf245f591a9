"""WGS84 geodesy written out for the checks and benchmarks that compare sextant's geodetic outputs with an
independent computation (not GeographicLib, which sextant uses): a point's Earth-centred coordinates, and its
East-North-Up coordinates in the tangent plane at an origin.  Angles in degrees, heights above the ellipsoid in
metres."""
import math

A, F = 6378137.0, 1 / 298.257223563  # WGS84's semi-major axis (m) and flattening
E2 = F * (2 - F)


def ecef(lat, lon, alt):
    """Earth-centred, Earth-fixed x, y, z (m) of a geodetic point."""
    la, lo = math.radians(lat), math.radians(lon)
    n = A / math.sqrt(1 - E2 * math.sin(la) ** 2)
    return ((n + alt) * math.cos(la) * math.cos(lo), (n + alt) * math.cos(la) * math.sin(lo),
            (n * (1 - E2) + alt) * math.sin(la))


def enu(origin, lat, lon, alt):
    """East, North, Up (m) of (lat, lon, alt) in the tangent plane at origin = (lat, lon, alt)."""
    la, lo = math.radians(origin[0]), math.radians(origin[1])
    o, p = ecef(*origin), ecef(lat, lon, alt)
    d = [p[i] - o[i] for i in range(3)]
    e = -math.sin(lo) * d[0] + math.cos(lo) * d[1]
    n = -math.sin(la) * math.cos(lo) * d[0] - math.sin(la) * math.sin(lo) * d[1] + math.cos(la) * d[2]
    u = math.cos(la) * math.cos(lo) * d[0] + math.cos(la) * math.sin(lo) * d[1] + math.sin(la) * d[2]
    return e, n, u
