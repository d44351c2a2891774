; Two separate towers, each turned upside down.
(define (problem two-towers-reversed)
  (:domain blocks3)
  (:objects a b c d e f - block)
  (:init (ontable a) (on b a) (on c b) (clear c) (ontable d) (on e d) (on f e) (clear f))
  (:goal (and (on a b) (on b c) (on d e) (on e f))))
