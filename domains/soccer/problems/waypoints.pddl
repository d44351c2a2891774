; Sec. 5.5.2, Fig. 5.15: from its start pose p0 the robot passes the four way-points w1..w4 in turn.
(define (problem waypoints)
  (:domain soccer)
  (:objects p0 w1 w2 w3 w4 - pos)
  (:init (robot p0)
         (waypoint w1) (waypoint w2) (waypoint w3) (waypoint w4)
         (next p0 w1) (next w1 w2) (next w2 w3) (next w3 w4)
         (final w4))
  (:goal (and (visited w1) (visited w2) (visited w3) (visited w4) (final w4))))
