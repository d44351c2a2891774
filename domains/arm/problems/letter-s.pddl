; A second letter, 'S' (the initial of a co-author of Stulp et al. 2007, Sec. 5.5), through six way-points.
(define (problem letter-s)
  (:domain arm)
  (:objects s1 s2 s3 s4 s5 s6 - waypoint)
  (:init (at s1)
         (next s1 s2) (next s2 s3) (next s3 s4) (next s4 s5) (next s5 s6)
         (rest s6))
  (:goal (and (reached s2) (reached s3) (reached s4) (reached s5) (reached s6)
              (at s6) (rest s6))))
