; Three independent goals: three pairs stacked from the table.
(define (problem three-pairs)
  (:domain blocks3)
  (:objects a b c d e f - block)
  (:init (ontable a) (ontable b) (ontable c) (ontable d) (ontable e) (ontable f)
         (clear a) (clear b) (clear c) (clear d) (clear e) (clear f))
  (:goal (and (on a b) (on c d) (on e f))))
