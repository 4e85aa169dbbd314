"""The planner's sampling steps, in one place (metres of arc length).

A path is kept as polylines with the heading and curvature at their vertices: straights by their
two ends, turns at the step they were integrated with, headland rings at the step their rounded
corners were cut into. Everything finer is evaluated on demand (fields.planner.path).
"""

TURN_STEP = 0.05       # m: integration step of the continuous-curvature turns (fields.planner.curves)
POLYLINE_STEP = 0.5    # m: vertex spacing of the headland rings; straights are checked inside the field this often
ROUTE_STEP = 0.1       # m: the trackers' grid: the route component projects the vehicle onto the path this finely
EXPORT_STEP = 0.5      # m: route.csv and route.geojson rows at most this far apart where the path curves or the
                       #    speed changes (a straight between them is written by its ends)
