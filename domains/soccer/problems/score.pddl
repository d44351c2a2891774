; Fig. 5.6: the robot at pos1 approaches the ball at pos2 and dribbles it to the target pose pos3.
(define (problem score)
  (:domain soccer)
  (:objects pos1 pos2 pos3 - pos)
  (:init (robot pos1) (ball pos2) (final pos3))
  (:goal (and (atball pos3) (final pos3))))
