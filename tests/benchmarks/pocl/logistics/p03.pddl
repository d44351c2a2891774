; Two cities, a truck in each, one airplane; five packages, some sharing a truck leg or the flight.
(define (problem two-cities-five-packages)
  (:domain logistics)
  (:objects c1 c2 - city c1-po c2-po - location c1-ap c2-ap - airport
            t1 t2 - truck plane - airplane p1 p2 p3 p4 p5 - package)
  (:init (in-city c1-po c1) (in-city c1-ap c1) (in-city c2-po c2) (in-city c2-ap c2)
         (at t1 c1-po) (at t2 c2-ap) (at plane c1-ap)
         (at p1 c1-po) (at p2 c1-po) (at p3 c2-ap) (at p4 c1-ap) (at p5 c2-po))
  (:goal (and (at p1 c1-ap) (at p2 c2-po) (at p3 c2-po) (at p4 c2-ap) (at p5 c2-ap))))
